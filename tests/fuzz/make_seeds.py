#!/usr/bin/python3
"""Writes the fuzz targets' seed corpora (tests/fuzz/corpus/<target>/): small valid inputs of
every kind each parser reads, and a few near misses. Run once; the files are committed."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))

TETRA = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
FACES = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def put(target, name, data):
    folder = os.path.join(HERE, "corpus", target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as out:
        out.write(data if isinstance(data, bytes) else data.encode())


def obj():
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in TETRA) + "".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in FACES)
    put("fuzz_obj", "tetra.obj", text)
    put("fuzz_obj", "attributes.obj", "".join(f"v {x} {y} {z} 0.5 0.25 1\n" for x, y, z in TETRA) +
        "".join(f"vt {x} {y}\n" for x, y, _ in TETRA) + "".join("vn 0 0 1\n" for _ in TETRA) +
        "".join(f"f {a+1}/{a+1}/{a+1} {b+1}/{b+1}/{b+1} {c+1}/{c+1}/{c+1}\n" for a, b, c in FACES))
    put("fuzz_obj", "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -1 -2 -3\n# comment\nl 1 2\n")


def off():
    put("fuzz_off", "tetra.off", f"OFF\n4 4 6\n" + "".join(f"{x} {y} {z}\n" for x, y, z in TETRA) +
        "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES))
    put("fuzz_off", "stcn.off", "STCNOFF\n4 4 0\n" + "".join(f"{x} {y} {z} 0 0 1 255 0 0 255 {x} {y}\n" for x, y, z in TETRA) +
        "".join(f"3 {a} {b} {c} 0.5 0.5 0.5\n" for a, b, c in FACES))
    put("fuzz_off", "counts-apart.off", "OFF # header\n# comment\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")


def ply():
    vertex = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    face = "element face 4\nproperty list uchar int vertex_indices\n"
    put("fuzz_ply", "ascii.ply", "ply\nformat ascii 1.0\n" + vertex + face + "end_header\n" +
        "".join(f"{x} {y} {z}\n" for x, y, z in TETRA) + "".join(f"3 {a} {b} {c}\n" for a, b, c in FACES))
    for order, code in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        header = (f"ply\nformat {order} 1.0\ncomment seed\nelement vertex 4\nproperty double x\nproperty double y\n"
                  "property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty float nx\n"
                  "element face 4\nproperty list uchar uint vertex_indices\nproperty ushort label\n"
                  "element other 1\nproperty list uchar float values\nend_header\n").encode()
        body = b"".join(struct.pack(code + "dddBBBf", x, y, z, 10, 20, 30, 1.0) for x, y, z in TETRA)
        body += b"".join(struct.pack(code + "BIIIH", 3, a, b, c, 7) for a, b, c in FACES)
        body += struct.pack(code + "Bff", 2, 1.5, 2.5)
        put("fuzz_ply", f"{order}.ply", header + body)


def stl():
    def normal_line(t):
        return "facet normal 0 0 1\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in t) + "endloop\nendfacet\n"
    tris = [[TETRA[i] for i in f] for f in FACES]
    put("fuzz_stl", "text.stl", "solid seed\n" + "".join(normal_line(t) for t in tris) + "endsolid seed\n")
    data = b"seed binary STL".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        data += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *p) for p in t) + struct.pack("<H", 0)
    put("fuzz_stl", "binary.stl", data)


def numbers():
    for i, text in enumerate(["0", "-0", "1e308", "4.9406564584124654e-324", "2.2250738585072014e-308", "+7.125",
                              "0.1", "123456789012345678901234567890", "1e-400", "nan", "inf", "1.", ".5", "1e+",
                              "9007199254740993", "-1.7976931348623157e308"]):
        put("fuzz_numbers", f"n{i}", text)


def giscup():
    with open(os.path.join(ROOT, "testdata", "giscup14", "td1", "lines_out.txt")) as f:
        lines = f.read().splitlines()
    put("fuzz_giscup", "td1-head.txt", "\n".join(lines[:3]) + "\n")
    with open(os.path.join(ROOT, "testdata", "giscup14", "td1", "points_out.txt")) as f:
        put("fuzz_giscup", "td1-points.txt", "\n".join(f.read().splitlines()[:3]) + "\n")
    put("fuzz_giscup", "small.txt", '7:<gml:LineString srsName="EPSG:54004"><gml:coordinates decimal="." cs="," ts=" ">'
        "1,2 3.5,4 -5e3,6</gml:coordinates></gml:LineString>\n")


def gpkg_blob():
    def header(envelope=0, empty=False, little=True):
        flags = (envelope << 1) | (1 if little else 0) | (0x10 if empty else 0)
        return b"GP\x00" + bytes([flags]) + struct.pack("<i", 4326) + b"\x00" * {0: 0, 1: 32, 2: 48, 3: 48, 4: 64}[envelope]
    put("fuzz_gpkg_blob", "point", header() + struct.pack("<BIdd", 1, 1, 1.5, 2.5))
    put("fuzz_gpkg_blob", "point-z-big", header(1) + struct.pack(">BIddd", 0, 1001, 1.5, 2.5, 3.5))
    put("fuzz_gpkg_blob", "multipoint", header() + struct.pack("<BII", 1, 4, 2) + struct.pack("<BIdd", 1, 1, 0, 0) +
        struct.pack("<BIdd", 1, 1, 3, 4))
    put("fuzz_gpkg_blob", "empty", header(empty=True) + struct.pack("<BIdd", 1, 1, float("nan"), float("nan")))


def gpkg_file():
    # Whole files: a table "points" (fid, geom) as read_gpkg_points reads it, small pages.
    import sqlite3
    import tempfile
    def header():
        return b"GP\x00\x01" + struct.pack("<i", 4326)
    def point(x, y):
        return header() + struct.pack("<BIdd", 1, 1, x, y)
    for name, rows in (("few", [(1, point(1.5, 2.5)), (2, None), (5, point(3, 4))]),
                       ("far-fids", [(-(2 ** 63), point(0, 0)), (2 ** 62, point(1, 1))]),
                       ("split", [(1, point(0, 0)), (70000, point(1, 1)), (140001, point(2, 2)),
                                  (140002, header() + struct.pack("<BIIBIdd", 1, 4, 1, 1, 1, 5, 6))])):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "seed.gpkg")
            db = sqlite3.connect(path)
            db.execute("PRAGMA page_size = 512")
            db.execute("CREATE TABLE points (fid INTEGER PRIMARY KEY, geom BLOB)")
            db.executemany("INSERT INTO points VALUES (?, ?)", rows)
            db.commit()
            db.execute("VACUUM")
            db.close()
            with open(path, "rb") as f:
                put("fuzz_gpkg_file", name, f.read())


def shapefile():
    # The fuzz input: .shx length and .dbf length (16 bits each), then .shx, .dbf, .shp.
    def shp_header(shape_type, length_bytes):
        return (struct.pack(">7i", 9994, 0, 0, 0, 0, 0, length_bytes // 2) + struct.pack("<2i", 1000, shape_type) +
                struct.pack("<8d", 0, 0, 10, 10, 0, 0, 0, 0))
    def files(shape_type, contents):
        records, index, at = b"", b"", 100
        for number, content in enumerate(contents, 1):
            records += struct.pack(">2i", number, len(content) // 2) + content
            index += struct.pack(">2i", at // 2, len(content) // 2)
            at += 8 + len(content)
        shp = shp_header(shape_type, 100 + len(records)) + records
        shx = shp_header(shape_type, 100 + len(index)) + index
        dbf = struct.pack("<BBBBIHH20x", 3, 26, 11, 26, len(contents), 33 + 32 * 0 + 1, 1) + b"\r"
        dbf = bytes(dbf[:32]) + b"\r" + b" " * len(contents) + b"\x1a"
        dbf = dbf[:4] + struct.pack("<I", len(contents)) + struct.pack("<HH", 33, 1) + dbf[12:]
        return struct.pack(">HH", len(shx), len(dbf)) + shx + dbf + shp
    points = [struct.pack("<idd", 1, 1.5, 2.5), struct.pack("<idd", 1, 3, 4), struct.pack("<i", 0)]
    put("fuzz_shapefile", "points", files(1, points))
    line = struct.pack("<i4dii", 3, 0, 0, 2, 2, 1, 3) + struct.pack("<i", 0) + struct.pack("<6d", 0, 0, 1, 1, 2, 0)
    put("fuzz_shapefile", "polyline", files(3, [line]))
    multi = struct.pack("<i4di", 8, 0, 0, 1, 1, 2) + struct.pack("<4d", 0, 0, 1, 1)
    put("fuzz_shapefile", "multipoint", files(8, [multi]))


for make in (obj, off, ply, stl, numbers, giscup, gpkg_blob, gpkg_file, shapefile):
    make()
