#!/usr/bin/env python3
"""toposimp against its peers on the same data, on the same machine, in the same run.

For each dataset and target (--keep 50%, 10%, 1% and --max) it times toposimp (exact, float, rational;
1 thread and all threads), mapshaper (-simplify visvalingam, at the fraction toposimp kept), ogr2ogr -simplify (GEOS
TopologyPreservingSimplifier, tolerance searched to the same fraction) and, on polygon layers, GEOS ≥ 3.12's
CoverageSimplifier (build/peers/coverage_simplify from scripts/bench/build-geos.sh, when built; tolerance
searched likewise) with /usr/bin/time over
several runs, checks every output with `toposimp check` against the same control points, and
writes BENCHMARKS.md (medians and ratios), with toposimp's phases per mode and thread count in the
layout of the dissertation's Tables 3.1/3.2. Data: scripts/bench/fetch-data.sh.

  scripts/bench/run.py [--data DIR] [--runs N] [--datasets td1,td2,ne,gshhg] [--targets 50%,10%,1%,max]
                      [--out BENCHMARKS.md] [--append]
"""
import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
# Inputs with more vertices than this are not run with --arithmetic rational (said in their section).
RATIONAL_LIMIT = 500_000

DATASETS = {
    'td1': dict(lines='td1_lines.shp', points='td1_points.shp', title='GIS Cup 2014 td1 (NH county borders)'),
    'td2': dict(lines='td2_lines.shp', points='td2_points.shp', title='GIS Cup 2014 td2 (MA county borders)'),
    'ne': dict(lines='ne_states.shp', points='cities.shp', title='Natural Earth states/provinces (polygons) + GeoNames cities',
               polygons=True),
    'gshhg': dict(lines='gshhg.shp', points='gshhg_points.gpkg',
                  title='GSHHG full-resolution shorelines, level 1 + 10 M control points'),
}


def timed(command, runs, phases=None):
    """Runs `command` `runs` times; returns medians of wall and CPU seconds and the peak RSS. Wall
    time is measured here around /usr/bin/time (its %e has 10 ms steps, too coarse for the GIS Cup
    files; the wrapper's own cost is the same for every tool). With `phases` (a dict), the command
    prints toposimp's --json; the medians of its phase times go there."""
    walls, cpus, rss, reports = [], [], 0, []
    for _ in range(runs):
        with tempfile.NamedTemporaryFile('r') as out:
            start = time.perf_counter()
            result = subprocess.run(['/usr/bin/time', '-o', out.name, '-f', '%U %S %M'] + command,
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            wall = time.perf_counter() - start
            if result.returncode not in (0, 1):
                raise RuntimeError('%s failed:\n%s' % (' '.join(command), result.stderr[-2000:]))
            user, system, kb = out.read().split()[-3:]
        walls.append(wall)
        cpus.append(float(user) + float(system))
        rss = max(rss, int(kb))
        if phases is not None:
            reports.append(json.loads(result.stdout))
    if phases is not None:
        def median(get):
            return statistics.median(get(r) for r in reports)
        phases.update(read=median(lambda r: r['seconds']['read']),
                      initialize=median(lambda r: r['engine_seconds']['index'] + r['engine_seconds']['crossings']),
                      simplify=median(lambda r: r['engine_seconds']['sweep']),
                      write=median(lambda r: r['seconds']['write']), total=median(lambda r: r['seconds']['total']),
                      threads=reports[0]['parallel']['threads'], rounds=reports[0]['parallel']['rounds'],
                      removed=reports[0]['removed'])
    return statistics.median(walls), statistics.median(cpus), rss / 1024.0


def vertex_count(path):
    layer = os.path.splitext(os.path.basename(path))[0]
    out = subprocess.run(['ogrinfo', '-q', '-dialect', 'SQLite', '-sql',
                          'SELECT SUM(ST_NPoints(geometry)) AS n FROM "%s"' % layer, path],
                         capture_output=True, text=True).stdout
    for line in out.splitlines():
        if '=' in line:
            return int(line.split('=')[1])
    raise RuntimeError('cannot count vertices of ' + path)


def check(binary, original, simplified, points, limit=180):
    try:
        result = subprocess.run([binary, 'check', original, simplified, '-p', points, '--json'], capture_output=True,
                                text=True, timeout=limit)
    except subprocess.TimeoutExpired:
        return 'not finished in %d s' % limit
    if result.returncode == 2:
        return 'error: ' + result.stderr.strip()[:200]
    report = json.loads(result.stdout)
    total = sum(report['counts'].values())
    worst = sorted(((n, k) for k, n in report['counts'].items() if n), reverse=True)[:3]
    return '%d' % total + (' (%s)' % ', '.join('%s %d' % (k, n) for n, k in worst) if worst else '')


def remove_shapefile(path):
    base = os.path.splitext(path)[0]
    for ext in ('.shp', '.shx', '.dbf', '.prj', '.cpg'):
        if os.path.exists(base + ext):
            os.remove(base + ext)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--data', default=os.environ.get('TOPOSIMP_BENCH_DATA', os.path.join(REPO, 'build', 'bench-data')))
    parser.add_argument('--binary', default=os.path.join(REPO, 'build', 'release', 'toposimp'))
    parser.add_argument('--runs', type=int, default=3)
    parser.add_argument('--datasets', default='td1,td2,ne,gshhg')
    parser.add_argument('--targets', default='50%,10%,1%,max')
    parser.add_argument('--coverage', default=os.path.join(REPO, 'build', 'peers', 'coverage_simplify'),
                        help="GEOS CoverageSimplifier driver (scripts/bench/build-geos.sh); skipped if absent")
    parser.add_argument('--out', default=os.path.join(REPO, 'BENCHMARKS.md'))
    parser.add_argument('--append', action='store_true', help='add the datasets to an existing report')
    args = parser.parse_args()
    data = os.path.abspath(args.data)
    mapshaper = os.path.join(data, 'node_modules', '.bin', 'mapshaper')
    work = tempfile.mkdtemp(prefix='toposimp-bench-')
    sections = []
    for name in args.datasets.split(','):
        spec = DATASETS[name]
        lines, points = os.path.join(data, spec['lines']), os.path.join(data, spec['points'])
        total = vertex_count(lines)
        runs = args.runs
        rows, phase_rows, identical = [], [], []
        for target in args.targets.split(','):
            def out(tag):
                return os.path.join(work, '%s_%s_%s.shp' % (name, target.strip('%'), tag))
            flag = ['--keep', target] if target != 'max' else ['--max']
            ours = out('toposimp')
            results, phases = {}, {}
            for mode in ('exact', 'float', 'rational'):
                if mode == 'rational' and total > RATIONAL_LIMIT:
                    continue  # ten times slower: shown on the smaller sets only
                for threads in (1, os.cpu_count()):
                    tag = 'toposimp %s, %d thread%s' % (mode, threads, 's' if threads > 1 else '')
                    path = out('toposimp_%s_%d' % (mode, threads))
                    command = [args.binary, 'map', lines, '-p', points, *flag, '--arithmetic', mode, '-j', str(threads),
                               '-o', path, '--overwrite', '-q', '--json']
                    phases[(mode, threads)] = {}
                    results[tag] = (path, timed(command, runs, phases[(mode, threads)]))
            base_tag = 'toposimp exact, %d threads' % os.cpu_count()
            for mode in ('exact', 'float', 'rational'):
                if (mode, 1) in phases:
                    a, b = out('toposimp_%s_1' % mode), out('toposimp_%s_%d' % (mode, os.cpu_count()))
                    same = all(open(a[:-4] + ext, 'rb').read() == open(b[:-4] + ext, 'rb').read() for ext in ('.shp', '.dbf'))
                    identical.append('%s %s: %s' % (target, mode, 'identical' if same else 'DIFFERENT'))
            for (mode, threads), p in sorted(phases.items()):
                one = phases[(mode, 1)]
                phase_rows.append('| %s | %s | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %d |' % (
                    target, mode, threads, p['read'], p['initialize'], p['simplify'], p['write'], p['total'],
                    one['simplify'] / p['simplify'] if p['simplify'] else 0, p['rounds']))
            shutil.copy(results[base_tag][0], ours)
            for ext in ('.shx', '.dbf', '.prj'):
                base = os.path.splitext(results[base_tag][0])[0]
                if os.path.exists(base + ext):
                    shutil.copy(base + ext, os.path.splitext(ours)[0] + ext)
            kept = vertex_count(ours)
            share = kept / total
            # mapshaper: same share of vertices (its percentage counts removable vertices; close enough, counts shown).
            path = out('mapshaper')
            command = [mapshaper, '-i', lines, '-simplify', 'visvalingam', 'keep-shapes', '%.4f%%' % (100 * share), '-o', path, 'force']
            results['mapshaper'] = (path, timed(command, runs))
            # ogr2ogr -simplify and GEOS's CoverageSimplifier: tolerance searched (bisection on a log
            # scale) to keep about as many vertices.
            def searched(tag, make):
                lo, hi = 1e-9, 1e6
                best = None
                for _ in range(14 if total < 2_000_000 else 7):
                    tolerance = (lo * hi) ** 0.5
                    path = out(tag)
                    remove_shapefile(path)
                    subprocess.run(make(path, tolerance), check=True, capture_output=True)
                    n = vertex_count(path)
                    if best is None or abs(n - kept) < abs(best[1] - kept):
                        best = (tolerance, n)
                    if n > kept:
                        lo = tolerance
                    else:
                        hi = tolerance
                path = out(tag)
                remove_shapefile(path)
                return path, make(path, best[0]), best[0]
            path, command, tolerance = searched('ogr2ogr', lambda path, t: ['ogr2ogr', path, lines, '-simplify', '%g' % t])
            results['ogr2ogr -simplify %g' % tolerance] = (path, timed(command, runs))
            if spec.get('polygons') and os.path.exists(args.coverage):
                path, command, tolerance = searched('geos_coverage', lambda path, t: [args.coverage, lines, path, '%g' % t])
                results['GEOS CoverageSimplifier %g' % tolerance] = (path, timed(command, runs))
            base_wall = results[base_tag][1][0]
            for tool, (path, (wall, cpu, rss)) in results.items():
                rows.append('| %s | %s | %d (%.1f%%) | %.3f | %.2f | %.0f | %.2f | %s |' % (
                    target, tool, vertex_count(path), 100.0 * vertex_count(path) / total, wall, cpu, rss,
                    wall / base_wall if base_wall else 0, check(args.binary, lines, path, points)))
        skipped = (' `--arithmetic rational` not run (over %d vertices; about ten times slower than exact, shown on the '
                   'smaller sets).' % RATIONAL_LIMIT) if total > RATIONAL_LIMIT else ''
        sections.append('### %s\n\n`%s` (%d vertices), control points `%s`; %d run(s) per measurement.%s\n\n'
                        '| target | tool | vertices kept | wall s (median) | CPU s | peak RSS MB | wall / toposimp exact, all threads | `toposimp check` violations |\n'
                        '|---|---|---|---|---|---|---|---|\n%s\n\n'
                        'toposimp\'s phases (seconds, medians; as the dissertation\'s Tables 3.1/3.2: *initialize* = point '
                        'grid, chains, shared locations and input crossings; *simplify* = removing vertices):\n\n'
                        '| target | arithmetic | threads | read | initialize | simplify | write | total | simplify speed-up vs 1 thread | rounds |\n'
                        '|---|---|---|---|---|---|---|---|---|---|\n%s\n\n'
                        'Output files (.shp and .dbf) of 1 thread vs %d threads: %s.\n' % (
                            spec['title'], spec['lines'], total, spec['points'], runs, skipped, '\n'.join(rows), '\n'.join(phase_rows),
                            os.cpu_count(), '; '.join(identical)) + '\n')
        print('done: ' + name, file=sys.stderr)
    cpu = next((l.split(':', 1)[1].strip() for l in open('/proc/cpuinfo') if l.startswith('model name')), platform.processor())
    memory = next((l.split()[1] for l in open('/proc/meminfo') if l.startswith('MemTotal')), '?')
    versions = [subprocess.run([args.binary, '--version'], capture_output=True, text=True).stdout.strip(),
                'mapshaper ' + subprocess.run([mapshaper, '-v'], capture_output=True, text=True).stdout.strip(),
                subprocess.run(['ogr2ogr', '--version'], capture_output=True, text=True).stdout.strip()]
    if os.path.exists(args.coverage):
        geos_config = os.path.join(os.path.dirname(args.coverage), 'geos', 'bin', 'geos-config')
        version = subprocess.run([geos_config, '--version'], capture_output=True, text=True).stdout.strip() if os.path.exists(geos_config) else '?'
        versions.append('GEOS %s (CoverageSimplifier, built from source)' % version)
    if args.append:
        with open(args.out, 'a') as f:
            f.write('\nAppended by `scripts/bench/run.py %s` on %s.\n\n%s' % (' '.join(sys.argv[1:]), time.strftime('%Y-%m-%d'), '\n'.join(sections)))
        shutil.rmtree(work)
        print('appended to ' + args.out, file=sys.stderr)
        return
    # Every section after the generated map tables (each a `## ` heading: earlier runs, precision,
    # levels, the mesh benchmark of scripts/bench/mesh.py) is kept as it is.
    kept_after = ''
    if os.path.exists(args.out):
        previous = open(args.out).read()
        if '\n## ' in previous:
            kept_after = '\n' + previous[previous.index('\n## ') + 1:]
    with open(args.out, 'w') as f:
        f.write('# Benchmarks\n\nGenerated by `scripts/bench/run.py %s` on %s — do not edit by hand.\n\n'
                'Machine: %s, %d cores, %.0f GiB. %s.\n\n'
                'toposimp runs on 1 thread and on all threads (`-j`); its output is byte-identical either way. '
                'Vertices are counted in the written features (a border shared by two polygons counts twice). '
                'Every output is checked against the input and the same control points with `toposimp check` '
                '(exact). mapshaper, ogr2ogr and GEOS\'s CoverageSimplifier have no control points: their violations are what they would '
                'break.\n\n%s' % (
                    ' '.join(sys.argv[1:]), time.strftime('%Y-%m-%d'), cpu, os.cpu_count(), int(memory) / 1048576,
                    '; '.join(versions), '\n'.join(sections)) + kept_after)
    shutil.rmtree(work)
    print('wrote ' + args.out, file=sys.stderr)


if __name__ == '__main__':
    main()
