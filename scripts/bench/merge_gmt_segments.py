#!/usr/bin/env python3
"""Joins GMT multisegment text (gmt coast -M: pieces cut at GSHHG's bin edges) back into lines.

Pieces that meet end to end at exactly the same coordinate text are joined; closed results are
rings. Writes GeoJSON (coordinates copied as text, so nothing is rounded; a CSV row would be too
long for GDAL's CSV reader: Eurasia alone is over a million vertices)."""
import sys
from collections import defaultdict


def read_pieces(path):
    pieces, current = [], []
    with open(path) as f:
        for line in f:
            if line.startswith('>'):
                if len(current) >= 2:
                    pieces.append(current)
                current = []
            else:
                x, y = line.split()[:2]
                if current and current[-1] == (x, y):
                    continue
                current.append((x, y))
    if len(current) >= 2:
        pieces.append(current)
    return pieces


def merge(pieces):
    starts, ends = defaultdict(list), defaultdict(list)
    for i, p in enumerate(pieces):
        starts[p[0]].append(i)
        ends[p[-1]].append(i)
    used = [False] * len(pieces)

    def take(candidates):
        for j in candidates:
            if not used[j]:
                used[j] = True
                return j
        return None

    lines = []
    for i in range(len(pieces)):
        if used[i]:
            continue
        used[i] = True
        line = list(pieces[i])
        while line[0] != line[-1]:  # extend forwards
            j = take(starts[line[-1]])
            if j is None:
                break
            line.extend(pieces[j][1:])
        while line[0] != line[-1]:  # and backwards
            j = take(ends[line[0]])
            if j is None:
                break
            line[:0] = pieces[j][:-1]
        lines.append(line)
    return lines


def main():
    pieces = read_pieces(sys.argv[1])
    lines = merge(pieces)
    with open(sys.argv[2], 'w') as out:
        out.write('{"type":"FeatureCollection","name":"gshhg","features":[\n')
        for i, line in enumerate(lines):
            out.write('%s{"type":"Feature","properties":{"id":%d},"geometry":{"type":"LineString","coordinates":[%s]}}\n' % (
                ',' if i else '', i, ','.join('[%s,%s]' % p for p in line)))
        out.write(']}\n')
    print('%d pieces -> %d lines, %d vertices' % (len(pieces), len(lines), sum(len(l) for l in lines)), file=sys.stderr)


if __name__ == '__main__':
    main()
