#!/usr/bin/env python3
"""Writes the bundled sample in samples/katoomba/: a synthetic terrain near Katoomba NSW (150.31E 33.71S) in
GDA2020 lon/lat. Contours (PolyLineZ shapefile, DBF field ELEV) come from marching squares on a smooth
function, DEM points (XYZ text) sample the same function, building footprints (PolygonZ shapefile) sit where no
contour passes and do not overlap. Standard library only; the shapefile bytes are written here. Deterministic:
fixed seed, coordinates rounded to 1e-8 degrees and heights to 1 cm (so the last bits of math.sin on another
platform do not show). Checks its own output: no contour crosses another, no building touches a contour or
another building.

Usage: python3 samples/make_sample.py [output folder, default samples/katoomba]
"""
import math
import os
import random
import struct
import sys

SEED = 20240611
LON0, LAT0 = 150.300, -33.720  # south-west corner
WIDTH, HEIGHT = 1800.0, 2000.0  # metres east and north
M_PER_DEG_LAT = 110946.0  # near 33.7S; the exact value only sets the sample's shape
M_PER_DEG_LON = 111320.0 * math.cos(math.radians(33.71))
CONTOUR_STEP = 10.0
GRID_NX, GRID_NY = 150, 166  # marching-squares cells, about 12 m
DEM_NX, DEM_NY = 60, 64  # jittered DEM samples
BUILDINGS = 40
BUILDING_CLEARANCE = 4.0  # metres between a footprint and any contour or other footprint

GDA2020_PRJ = ('GEOGCS["GCS_GDA2020",DATUM["D_GDA2020",SPHEROID["GRS_1980",6378137.0,298.257222101]],'
               'PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]]')


def make_terrain(rng):
    """A plateau around 1000 m falling to a valley in the south (like the Jamison Valley), with low hills."""
    bumps = [(rng.uniform(0, WIDTH), rng.uniform(HEIGHT * 0.35, HEIGHT), rng.uniform(120, 320),
              rng.uniform(-18, 22)) for _ in range(9)]

    def z(x, y):
        v = 1015.0 + 8.0 * math.sin(x / 260.0) * math.cos(y / 310.0) + 0.004 * y
        # Escarpment: a smooth step of 170 m about a wavy line a third of the way up.
        edge = HEIGHT * 0.33 + 90.0 * math.sin(x / 330.0)
        v -= 170.0 / (1.0 + math.exp((y - edge) / 85.0))
        for bx, by, r, h in bumps:
            v += h * math.exp(-((x - bx) ** 2 + (y - by) ** 2) / (r * r))
        return v

    return z


def to_lonlat(x, y):
    return round(LON0 + x / M_PER_DEG_LON, 8), round(LAT0 + y / M_PER_DEG_LAT, 8)


def to_local(lon, lat):
    return (lon - LON0) * M_PER_DEG_LON, (lat - LAT0) * M_PER_DEG_LAT


def marching_squares(z, level):
    """Contour lines of z at level on the grid, as lists of local points; closed loops repeat their start."""
    dx, dy = WIDTH / GRID_NX, HEIGHT / GRID_NY
    val = [[z(i * dx, j * dy) for i in range(GRID_NX + 1)] for j in range(GRID_NY + 1)]
    for row in val:
        for i, v in enumerate(row):
            if v == level:  # keep crossings off grid nodes
                row[i] = v + 1e-9

    def point(edge):
        kind, i, j = edge  # 'h': (i,j)-(i+1,j); 'v': (i,j)-(i,j+1)
        a = val[j][i]
        b = val[j][i + 1] if kind == 'h' else val[j + 1][i]
        t = (level - a) / (b - a)
        return ((i + t) * dx, j * dy) if kind == 'h' else (i * dx, (j + t) * dy)

    links = {}

    def link(e1, e2):
        links.setdefault(e1, []).append(e2)
        links.setdefault(e2, []).append(e1)

    for j in range(GRID_NY):
        for i in range(GRID_NX):
            corners = [val[j][i], val[j][i + 1], val[j + 1][i + 1], val[j + 1][i]]
            edges = [('h', i, j), ('v', i + 1, j), ('h', i, j + 1), ('v', i, j)]  # bottom, right, top, left
            above = [c > level for c in corners]
            cut = [k for k in range(4) if above[k] != above[(k + 1) % 4]]
            if len(cut) == 2:
                link(edges[cut[0]], edges[cut[1]])
            elif len(cut) == 4:
                # Saddle: the cell centre decides which corners connect.
                centre_above = sum(corners) / 4 > level
                if centre_above == above[0]:
                    link(edges[0], edges[1])
                    link(edges[2], edges[3])
                else:
                    link(edges[3], edges[0])
                    link(edges[1], edges[2])
    lines = []
    seen = set()
    # Open lines start at boundary crossings (one link); loops at whatever is left.
    starts = sorted(e for e, l in links.items() if len(l) == 1) + sorted(links)
    for start in starts:
        if start in seen:
            continue
        chain = [start]
        seen.add(start)
        prev, cur = None, start
        while True:
            nxt = [e for e in links[cur] if e != prev and e not in seen]
            if not nxt:
                if len(chain) > 2 and start in links[cur] and prev is not None:
                    chain.append(start)  # closed loop
                break
            prev, cur = cur, nxt[0]
            seen.add(cur)
            chain.append(cur)
        lines.append([point(e) for e in chain])
    return lines


def segments_cross(p, q, r, s):
    """Proper or touching intersection of segments pq and rs."""
    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return (v > 0) - (v < 0)

    def on(a, b, c):
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    o1, o2, o3, o4 = orient(p, q, r), orient(p, q, s), orient(r, s, p), orient(r, s, q)
    if o1 != o2 and o3 != o4 and 0 not in (o1, o2, o3, o4):
        return True
    return ((o1 == 0 and on(p, q, r)) or (o2 == 0 and on(p, q, s)) or (o3 == 0 and on(r, s, p)) or
            (o4 == 0 and on(r, s, q)))


def check_contours(contours):
    """No two contour segments meet, except consecutive segments of one line at their shared vertex."""
    cell = 40.0
    buckets = {}
    segs = []
    for li, (_, pts) in enumerate(contours):
        local = [to_local(*p) for p in pts]
        for k in range(len(local) - 1):
            a, b = local[k], local[k + 1]
            assert a != b, 'repeated contour vertex'
            sid = len(segs)
            segs.append((li, k, a, b, len(local) - 1))
            for gx in range(int(min(a[0], b[0]) // cell), int(max(a[0], b[0]) // cell) + 1):
                for gy in range(int(min(a[1], b[1]) // cell), int(max(a[1], b[1]) // cell) + 1):
                    buckets.setdefault((gx, gy), []).append(sid)
    for ids in buckets.values():
        for x in range(len(ids)):
            for y in range(x + 1, len(ids)):
                l1, k1, a, b, n1 = segs[ids[x]]
                l2, k2, c, d, _ = segs[ids[y]]
                if l1 == l2 and (abs(k1 - k2) == 1 or abs(k1 - k2) == n1 - 1):
                    continue  # neighbours on one line (or the closing pair of a loop)
                assert not segments_cross(a, b, c, d), 'contours cross'


def place_buildings(rng, z, contours):
    """Rectangles and L-shapes, rotated, on the plateau where no contour passes."""
    seg_boxes = []
    for _, pts in contours:
        local = [to_local(*p) for p in pts]
        for a, b in zip(local, local[1:]):
            seg_boxes.append((min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1])))
    placed = []  # (footprint in local metres, box with clearance)
    tries = 0
    while len(placed) < BUILDINGS:
        tries += 1
        assert tries < 20000, 'cannot place the buildings'
        cx, cy = rng.uniform(60, WIDTH - 60), rng.uniform(HEIGHT * 0.5, HEIGHT - 60)
        w, h = rng.uniform(9, 22), rng.uniform(8, 16)
        angle = rng.uniform(0, math.pi / 2)
        if rng.random() < 0.35:  # L-shape: a w x h rectangle with a corner cut out
            cw, ch = w * rng.uniform(0.35, 0.6), h * rng.uniform(0.35, 0.6)
            shape = [(0, 0), (w, 0), (w, h - ch), (w - cw, h - ch), (w - cw, h), (0, h)]
        else:
            shape = [(0, 0), (w, 0), (w, h), (0, h)]
        ca, sa = math.cos(angle), math.sin(angle)
        ring = [(cx + (px - w / 2) * ca - (py - h / 2) * sa, cy + (px - w / 2) * sa + (py - h / 2) * ca)
                for px, py in shape]
        c = BUILDING_CLEARANCE
        box = (min(p[0] for p in ring) - c, min(p[1] for p in ring) - c,
               max(p[0] for p in ring) + c, max(p[1] for p in ring) + c)

        def overlaps(o):
            return not (o[2] < box[0] or o[0] > box[2] or o[3] < box[1] or o[1] > box[3])

        if any(overlaps(s) for s in seg_boxes) or any(overlaps(b) for _, b in placed):
            continue
        placed.append((ring, box))
    buildings = []
    for ring, _ in placed:
        ground = round(z(sum(p[0] for p in ring) / len(ring), sum(p[1] for p in ring) / len(ring)), 2)
        # Shapefile outer rings run clockwise: the shapes above are counter-clockwise, so reverse.
        ll = [to_lonlat(*p) for p in reversed(ring)]
        buildings.append((ground, round(rng.uniform(4, 12), 1), ll + [ll[0]]))
    return buildings


# ---- shapefile writing (ESRI Shapefile Technical Description, 1998) ----

def bbox(points):
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return min(xs), min(ys), max(xs), max(ys)


def write_shapefile(base, shape_type, records):
    """records: list of (parts, z) with parts a list of point lists (lon, lat) and z one height for all."""
    contents = []
    for parts, z in records:
        pts = [p for part in parts for p in part]
        rec = struct.pack('<i4d2i', shape_type, *bbox(pts), len(parts), len(pts))
        offset = 0
        for part in parts:
            rec += struct.pack('<i', offset)
            offset += len(part)
        rec += b''.join(struct.pack('<2d', *p) for p in pts)
        rec += struct.pack('<2d', z, z) + struct.pack('<%dd' % len(pts), *([z] * len(pts)))
        contents.append(rec)
    all_pts = [p for parts, _ in records for part in parts for p in part]
    zs = [z for _, z in records]

    def header(length_bytes):
        return (struct.pack('>7i', 9994, 0, 0, 0, 0, 0, length_bytes // 2) +
                struct.pack('<2i', 1000, shape_type) + struct.pack('<4d', *bbox(all_pts)) +
                struct.pack('<4d', min(zs), max(zs), 0.0, 0.0))

    shp_len = 100 + sum(8 + len(c) for c in contents)
    with open(base + '.shp', 'wb') as f:
        f.write(header(shp_len))
        for i, c in enumerate(contents):
            f.write(struct.pack('>2i', i + 1, len(c) // 2) + c)
    with open(base + '.shx', 'wb') as f:
        f.write(header(100 + 8 * len(contents)))
        offset = 100
        for c in contents:
            f.write(struct.pack('>2i', offset // 2, len(c) // 2))
            offset += 8 + len(c)
    with open(base + '.prj', 'w', newline='') as f:
        f.write(GDA2020_PRJ)


def write_dbf(path, fields, rows):
    """fields: (name, width, decimals) numeric fields; rows: tuples of numbers."""
    record_len = 1 + sum(w for _, w, _ in fields)
    header_len = 32 + 32 * len(fields) + 1
    out = struct.pack('<4BIHH20x', 3, 124, 1, 1, len(rows), header_len, record_len)  # dated 2024-01-01
    for name, width, dec in fields:
        out += struct.pack('<11sc4xBB14x', name.encode(), b'N', width, dec)
    out += b'\r'
    for row in rows:
        out += b' ' + b''.join(('%*.*f' % (w, d, v)).encode() for (_, w, d), v in zip(fields, row))
    out += b'\x1a'
    with open(path, 'wb') as f:
        f.write(out)


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                'katoomba')
    os.makedirs(out_dir, exist_ok=True)
    rng = random.Random(SEED)
    z = make_terrain(rng)

    corners = [z(x, y) for x in (0, WIDTH) for y in (0, HEIGHT)]
    lo = math.floor(min(corners + [z(WIDTH / 2, 0)]) / CONTOUR_STEP) * CONTOUR_STEP
    contours = []
    level = lo
    while level < 1100:
        for line in marching_squares(z, level):
            pts = [to_lonlat(*p) for p in line]
            dedup = [p for k, p in enumerate(pts) if k == 0 or p != pts[k - 1]]
            if len(dedup) >= 2:
                contours.append((level, dedup))
        level += CONTOUR_STEP
    check_contours(contours)

    buildings = place_buildings(rng, z, contours)

    write_shapefile(os.path.join(out_dir, 'contours'), 13, [([pts], lvl) for lvl, pts in contours])
    write_dbf(os.path.join(out_dir, 'contours.dbf'), [('ELEV', 8, 1)], [(lvl,) for lvl, _ in contours])
    write_shapefile(os.path.join(out_dir, 'buildings'), 15, [([ring], ground) for ground, _, ring in buildings])
    write_dbf(os.path.join(out_dir, 'buildings.dbf'), [('ID', 4, 0), ('GROUND', 8, 2), ('HEIGHT', 5, 1)],
              [(i + 1, g, h) for i, (g, h, _) in enumerate(buildings)])

    with open(os.path.join(out_dir, 'dem.xyz'), 'w', newline='\n') as f:
        f.write('lon lat elevation\n')
        for j in range(DEM_NY):
            for i in range(DEM_NX):
                x = (i + 0.5 + rng.uniform(-0.35, 0.35)) * WIDTH / DEM_NX
                y = (j + 0.5 + rng.uniform(-0.35, 0.35)) * HEIGHT / DEM_NY
                lon, lat = to_lonlat(x, y)
                f.write('%.8f %.8f %.2f\n' % (lon, lat, z(x, y)))

    print('%d contour lines (%d vertices), %d buildings, %d DEM points in %s' %
          (len(contours), sum(len(p) for _, p in contours), len(buildings), DEM_NX * DEM_NY, out_dir))


if __name__ == '__main__':
    main()
