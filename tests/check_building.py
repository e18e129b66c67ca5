#!/usr/bin/env python3
"""Checks the building generator examples/data/make_building.py: it is
deterministic (the committed presets are byte for byte what it writes), its
triangles have area, no two coplanar faces with the same facing overlap (an
exporter's duplicate faces make tracers pick either per pixel), and every
room, door, stair and lamp of the layout lies inside the building; by day
(--daylight) every window has its pane of glass and the layout its sky. Prints
"N passed, N failed" like the C test programs."""
import collections
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', 'examples', 'data')
passed = failed = 0


def check(name, ok, detail=''):
    global passed, failed
    if ok:
        passed += 1
        print('ok   ' + name)
    else:
        failed += 1
        print('FAIL ' + name + (': ' + detail if detail else ''))


def load(path):
    verts, tris = [], []
    for line in open(path):
        if line.startswith('v '):
            verts.append(tuple(float(x) for x in line.split()[1:4]))
        elif line.startswith('f '):
            tris.append(tuple(int(x.split('/')[0]) - 1 for x in line.split()[1:]))
    return verts, tris


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def overlap2d(p, q):
    """Separating axes of two triangles: True when they share interior (not
    just an edge or a corner); 1e-7 m absorbs the 0.1 mm rounding of the file."""
    for poly in (p, q):
        for i in range(3):
            a, b = poly[i], poly[(i + 1) % 3]
            nx, ny = b[1] - a[1], a[0] - b[0]
            pa = [nx * x + ny * y for x, y in p]
            qa = [nx * x + ny * y for x, y in q]
            if max(pa) <= min(qa) + 1e-7 or max(qa) <= min(pa) + 1e-7:
                return False
    return True


def geometry(path):
    verts, tris = load(path)
    zero, planes, skew = 0, collections.defaultdict(list), 0
    for t in tris:
        a, b, c = (verts[i] for i in t)
        n = cross(sub(b, a), sub(c, a))
        length = sum(x * x for x in n) ** 0.5
        if length < 1e-10:
            zero += 1
            continue
        ax = max(range(3), key=lambda k: abs(n[k]))
        if abs(n[ax]) < length * (1 - 1e-9):
            skew += 1          # the generator writes axis-aligned faces only
            continue
        uv = [k for k in range(3) if k != ax]
        planes[(ax, n[ax] > 0, round(a[ax], 4))].append([(verts[i][uv[0]], verts[i][uv[1]]) for i in t])
    dups = 0
    for tl in planes.values():
        boxes = [(min(x for x, _ in p), max(x for x, _ in p), min(y for _, y in p), max(y for _, y in p)) for p in tl]
        order = sorted(range(len(tl)), key=lambda i: boxes[i][0])
        for k, i in enumerate(order):
            for j in order[k + 1:]:
                if boxes[j][0] >= boxes[i][1]:
                    break
                if boxes[i][3] <= boxes[j][2] or boxes[j][3] <= boxes[i][2]:
                    continue
                dups += overlap2d(tl[i], tl[j])
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    return len(tris), zero, skew, dups, lo, hi


def layout_inside(path, lo, hi):
    bad = []
    for line in open(path):
        w = line.split()
        if not w or w[0].startswith('#'):
            continue
        if w[0] == 'room':
            box = [float(x) for x in w[4:10]]
        elif w[0] in ('door', 'window', 'stair'):
            box = [float(x) for x in w[2:8]]
        elif w[0] == 'lamp':
            x, y, z = (float(v) for v in w[4:7])
            box = [x, x, y, y, z, z]
        elif w[0] == 'sky' and len(w) == 4 and all(float(v) > 0 for v in w[1:]):
            continue
        else:
            bad.append(line.strip())
            continue
        for k in range(3):
            if box[2 * k] < lo[k] - 1e-6 or box[2 * k + 1] > hi[k] + 1e-6 or box[2 * k] > box[2 * k + 1]:
                bad.append(line.strip())
                break
    return bad


def daylight_ok(stem):
    """Two glass triangles per window, one sky line, no emitting material."""
    glass, material = 0, None
    for line in open(stem + '.obj'):
        if line.startswith('usemtl '):
            material = line.split()[1]
        elif line.startswith('f ') and material == 'glass':
            glass += 1
    layout = [l.split()[0] for l in open(stem + '.layout') if l.strip() and not l.startswith('#')]
    emitting = [l for l in open(stem + '.mtl') if l.startswith('Ke ')]
    return glass == 2 * layout.count('window') and layout.count('sky') == 1 and not emitting


def main():
    script = os.path.join(DATA, 'make_building.py')
    with tempfile.TemporaryDirectory() as tmp:
        for preset in ('1k', '4k', '1k_daylight'):
            out = os.path.join(tmp, 'building_' + preset)
            subprocess.run([sys.executable, script, '--preset', preset[:2], '--out', out] +
                           (['--daylight'] if 'daylight' in preset else []), check=True, stdout=subprocess.DEVNULL)
            for ext in ('.obj', '.mtl', '.layout'):
                committed = os.path.join(DATA, 'building_' + preset + ext)
                same = os.path.exists(committed) and open(committed, 'rb').read() == open(out + ext, 'rb').read()
                check('preset %s%s is what make_building.py writes' % (preset, ext), same,
                      'regenerate it: cd examples/data && python3 make_building.py --preset ' +
                      preset.replace('_daylight', ' --daylight'))
            n, zero, skew, dups, lo, hi = geometry(out + '.obj')
            target = {'1k': 1000, '4k': 4000}[preset[:2]]
            check('preset %s: %d triangles, about %d' % (preset, n, target), 0.7 * target <= n <= 1.4 * target)
            check('preset %s: no zero-area triangle' % preset, zero == 0, '%d' % zero)
            check('preset %s: every face axis-aligned' % preset, skew == 0, '%d' % skew)
            check('preset %s: no coplanar overlapping faces with the same facing' % preset, dups == 0, '%d pairs' % dups)
            bad = layout_inside(out + '.layout', lo, hi)
            check('preset %s: the layout lies inside the building' % preset, not bad, '; '.join(bad[:3]))
            if 'daylight' in preset:
                check('preset %s: a pane of glass in every window, a sky, no lamp on' % preset, daylight_ok(out))
        # Another seed and shape: the same checks hold beyond the presets.
        out = os.path.join(tmp, 'other')
        subprocess.run([sys.executable, script, '--floors', '3', '--rooms-x', '2', '--rooms-z', '3',
                        '--seed', '11', '--out', out], check=True, stdout=subprocess.DEVNULL)
        n, zero, skew, dups, lo, hi = geometry(out + '.obj')
        check('3 storeys of 2 x 3 rooms, seed 11: no zero-area, no overlapping duplicate',
              zero == 0 and skew == 0 and dups == 0, 'zero %d skew %d dups %d' % (zero, skew, dups))
        check('3 storeys of 2 x 3 rooms, seed 11: the layout lies inside', not layout_inside(out + '.layout', lo, hi))
    print('%d passed, %d failed' % (passed, failed))
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
