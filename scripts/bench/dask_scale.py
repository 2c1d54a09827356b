#!/usr/bin/python3
"""A generated map much bigger than a Dask worker may hold, simplified by python3 -m toposimp.dask
on workers whose memory is limited (Dask's memory_limit: a worker over it is stopped), against
toposimp map in one process: times, peak memory of the command and of each worker, the output byte
for byte, and toposimp check on it.

    scripts/bench/dask_scale.py BUILD_DIR [--cells 250] [--edge-vertices 40] [--rivers 2000]
                                [--river-steps 2000] [--points 2000000] [--workers 2]
                                [--memory-limit 1GiB] [--target "--keep 10%"] [--data DIR]
                                [--dask-options "--first-round here"] [--lines-only] [--cells-only [--z [zero|cell]]]
                                [--geopackage] [--no-check]

The map (generate_map.py --shapefiles) is written to --data (default build/bench-data/scale-N)
once. --lines-only: the rivers alone (a plain PolyLine Shapefile, written to a Shapefile: an
input that --first-round workers reads by parts) with the control points, no cells written (a
bigger --cells then spreads them, and fewer cross). --cells-only: the cells' coverage alone (a
plain Polygon Shapefile, written to a Shapefile: read by parts too) with the control points; with
--z, as a PolygonZ Shapefile (made once with ogr2ogr -dim XYZ; read by parts too): `zero`
(cellsz.shp) each vertex's Z 0, so every ring at a shared location has the same; `cell`
(cellsz_cell.shp) each cell's Z its id, so the rings at every shared location differ (the worst
case for the notes the plan keeps where they do).
--geopackage: the cells, rivers and roads as layers of one GeoPackage (map.gpkg beside the
Shapefiles, made once with ogr2ogr), an input --first-round workers reads by parts too.
Vertices are counted as the input stores them (a border shared by two cells twice) and as the map
holds them (once). Prints a Markdown table.
"""
import argparse
import os
import pathlib
import shlex
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import dask_bench  # noqa: E402
import generate_map  # noqa: E402

SAME_DATE = ["--config", "OGR_CURRENT_DATE", "2000-01-01T00:00:00Z"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build")
    parser.add_argument("--cells", type=int, default=250)
    parser.add_argument("--edge-vertices", type=int, default=40)
    parser.add_argument("--rivers", type=int, default=2000)
    parser.add_argument("--river-steps", type=int, default=2000)
    parser.add_argument("--points", type=int, default=2_000_000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--memory-limit", default="1GiB")
    parser.add_argument("--target", default="--keep 10%")
    parser.add_argument("--data")
    parser.add_argument("--dask-options", default="", help="more python3 -m toposimp.dask options")
    parser.add_argument("--lines-only", action="store_true", help="the rivers alone, Shapefile to Shapefile")
    parser.add_argument("--cells-only", action="store_true", help="the cells' coverage alone, Shapefile to Shapefile")
    parser.add_argument("--z", nargs="?", const="zero", choices=["zero", "cell"],
                        help="with --cells-only: the cells as a PolygonZ Shapefile, Z 0 or each cell's id")
    parser.add_argument("--geopackage", action="store_true", help="the cells, rivers and roads as one GeoPackage, not the folder")
    parser.add_argument("--no-check", action="store_true", help="no toposimp check of the output (e.g. the same bytes checked before)")
    a = parser.parse_args()
    build = pathlib.Path(a.build).resolve()
    data = pathlib.Path(a.data or f"build/bench-data/scale-{a.cells}").resolve()
    if not (data / "places.shp").exists():
        generate_map.generate_shapefiles(data, a.cells, a.edge_vertices, a.rivers, a.river_steps, 6, a.points, 1,
                                         with_cells=not a.lines_only)
    # As stored: the cells' rings (4 borders of K + 1 vertices and the closing one), the rivers,
    # the roads of 3. As the map holds them: each border once (K vertices and the corners).
    cell_points = a.cells ** 2 * (4 * (a.edge_vertices + 1) + 1)
    cell_vertices = 2 * a.cells * (a.cells + 1) * a.edge_vertices + (a.cells + 1) ** 2
    line_vertices = a.rivers * a.river_steps + 6 * 3
    vertices, distinct = cell_points + line_vertices, cell_vertices + line_vertices
    layers = ["-l", "cells", "-l", "rivers", "-l", "roads"]
    single_out, dask_out = data / "single.gpkg", data / "dask.gpkg"
    source = str(data)
    if a.lines_only or a.cells_only:
        vertices = distinct = a.rivers * a.river_steps
        if a.cells_only:
            vertices, distinct = cell_points, cell_vertices
        layers, source = [], str(data / ("cells.shp" if a.cells_only else "rivers.shp"))
        single_out, dask_out = data / "single.shp", data / "dask.shp"
        if a.z and a.cells_only:
            stem = "cellsz" if a.z == "zero" else "cellsz_cell"
            source = str(data / f"{stem}.shp")
            if not pathlib.Path(source).exists():
                import subprocess

                z = [] if a.z == "zero" else ["-zfield", "id"]
                subprocess.run(["ogr2ogr", str(data / f"{stem}.staging.shp"), str(data / "cells.shp"), "-dim", "XYZ", *z,
                                "-nln", f"{stem}.staging"], check=True)
                for extension in (".shp", ".shx", ".dbf", ".prj"):
                    if (data / f"{stem}.staging{extension}").exists():
                        (data / f"{stem}.staging{extension}").rename(data / f"{stem}{extension}")
    if a.geopackage:
        source = str(data / "map.gpkg")
        if not pathlib.Path(source).exists():
            import subprocess

            staging = data / "map.staging.gpkg"
            staging.unlink(missing_ok=True)
            for name in ("cells", "rivers", "roads"):
                subprocess.run(["ogr2ogr", "-f", "GPKG", *(["-update"] if staging.exists() else []), str(staging), str(data / f"{name}.shp")],
                               check=True)
            staging.rename(source)
    map_arguments = [source, *layers, "-p", str(data / "places.shp"), *shlex.split(a.target), "-q", "--overwrite", *SAME_DATE]
    single = dask_bench.timed([str(build / "toposimp"), "map", *map_arguments, "-o", str(single_out)])

    env = dict(dask_bench.CLEAN_ENV, PYTHONPATH=str(build / "python"))
    sys.path.insert(0, str(build / "python"))
    from distributed import Client, LocalCluster
    from toposimp import dask as toposimp_dask

    # The workers start as toposimp.dask's own LocalCluster's would (huge pages asked for,
    # jemalloc where installed, Dask's profiler off): what a user gets without --scheduler.
    import dask.config

    worker_env = toposimp_dask.local_worker_environment("auto", dask_bench.CLEAN_ENV)
    os.environ.update(worker_env)  # (read by the worker processes as they start)
    with dask.config.set(toposimp_dask.local_worker_config(dask_bench.CLEAN_ENV)):
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=None,
                               memory_limit=a.memory_limit)
    client = Client(cluster)
    distributed = dask_bench.timed([sys.executable, "-m", "toposimp.dask", "map", *map_arguments, "-o", str(dask_out),
                                    "--scheduler", cluster.scheduler_address, *shlex.split(a.dask_options)], env=env)
    peaks = dask_bench.worker_peaks(client)
    client.close()
    cluster.close()
    extensions = (".shp", ".shx", ".dbf") if a.lines_only or a.cells_only else (".gpkg",)
    identical = all(dask_out.with_suffix(e).read_bytes() == single_out.with_suffix(e).read_bytes() for e in extensions)
    check = None
    if not a.no_check:
        check = dask_bench.timed([str(build / "toposimp"), "check", source, str(dask_out), *layers, "-p", str(data / "places.shp")])
    names = ("rivers", "places") if a.lines_only else ("cells", "places") if a.cells_only else ("cells", "rivers", "roads", "places")
    sizes = {name: (data / f"{name}.shp").stat().st_size for name in names}
    print(f"map: {data}: {vertices / 1e6:.1f} M vertices as stored ({distinct / 1e6:.1f} M in the map, each shared border once) "
          f"and {a.points / 1e6:.1f} M control points "
          f"({sum(sizes.values()) / 2**20:.0f} MiB of .shp), `{a.target}`, {a.workers} workers limited to {a.memory_limit} each"
          + (f", toposimp.dask {a.dask_options}" if a.dask_options else "") + (", the rivers alone" if a.lines_only else "")
          + (", the cells alone" if a.cells_only else "") + (f" with Z (PolygonZ, {'0' if a.z == 'zero' else 'each cell its id'})" if a.cells_only and a.z else "")
          + (", as one GeoPackage" if a.geopackage else "") + "; workers with " + " ".join(f"{k}={v}" for k, v in worker_env.items()))
    print()
    print("| run | seconds | command peak MiB | worker peaks MiB | output identical |")
    print("|---|---|---|---|---|")
    print(f"| toposimp map | {single[0]:.1f} | {single[1]:.0f} |  | |")
    print(f"| toposimp.dask | {distributed[0]:.1f} | {distributed[1]:.0f} | {' / '.join(f'{p:.0f}' for p in peaks)} | "
          f"{'yes' if identical else 'NO'} |")
    if check:
        print(f"| toposimp check (dask output) | {check[0]:.1f} | {check[1]:.0f} | | clean |")


if __name__ == "__main__":
    main()
