#!/usr/bin/env python3
"""Writes a generated building as an engine or a CAD program exports it: an OBJ
of triangles (no quads), its MTL, and a small text file describing the layout.
Units are metres, +y is up. Deterministic: the same arguments give the same
bytes on every machine.

    python3 make_building.py --preset 4k              # building_4k.obj/.mtl/.layout here
    python3 make_building.py --floors 3 --rooms-x 4 --rooms-z 3 --seed 7 --out b
    python3 make_building.py --preset 1k --daylight   # building_1k_daylight.*

The building is a grid of rooms per storey (column widths and row depths vary
with the seed), stacked storeys with floor slabs 20 cm thick, and:
- walls with both faces: exterior walls 20 cm thick, interior walls 12 cm; a
  wall is cut into boxes around its openings, so the openings have reveals;
- doors between rooms (a spanning tree of the rooms of each storey plus a few
  more), an entrance on the ground floor, windows in every exterior wall;
- a straight staircase in the same room of every storey but the top one,
  through a hole in the slab above, with a balustrade around the hole;
- furniture by floor area: desks with chairs, shelves, cabinets, a table;
- emitting ceiling panels, pendant lamps or desk lamps in most rooms, and at
  least one room without a lamp of its own from 4 rooms up (a dark room);
- T-junctions where walls meet slabs and where walls meet walls: a slab top is
  one rectangle per storey (cut only around the stair hole), and the walls
  standing on it end on its interior; faces lying flat against another
  surface (the bottom of a wall on a slab, the back of a shelf on a wall) are
  left out, as an exporter that removes hidden faces would do.

No two solids interpenetrate, every triangle winds counter-clockwise seen from
outside its solid, and no two faces are coplanar and overlapping with the same
facing. The layout file lists rooms, doors, windows, stairs and lamps, one per
line, so tests and examples can place cameras, probes and moving objects:

    room STOREY I J X0 X1 Y0 Y1 Z0 Z1 LAMP STAIR   (LAMP: panel|pendant|desk|none)
    door STOREY X0 X1 Y0 Y1 Z0 Z1                  (the opening's box)
    window STOREY X0 X1 Y0 Y1 Z0 Z1
    stair STOREY X0 X1 Y0 Y1 Z0 Z1                 (bottom step at X0, rising to +x)
    lamp STOREY I J X Y Z KIND                     (centre of the emitting face)
    sky R G B [MAP]                                (--daylight: the sky's radiance; the walkthrough
                                                    also reads R G B times an equirectangular PFM map)

--daylight writes the same building by day: a pane of glass (Tf 0.85, illum 4:
thin glass, see examples/common/obj.h) in the middle of every window, facing
out; the lamps switched off (no Ke); a ground around the building at the
bottom of the ground slab, as wide as the building on each side; and a
constant overcast sky, given as the layout's `sky` line in W/(m^2 sr), which
lights the interior through the windows.

Presets: 1k (2 storeys of 2 x 1 rooms, 1,250 triangles), 4k (2 storeys of
3 x 3 rooms, 4,282), 16k (4 storeys of 5 x 4 rooms, 14,836) and 64k (8 storeys
of 7 x 7 rooms, 66,080). The 1k and 4k presets are committed beside this
script; `make bench` writes the larger ones under build/data."""

import argparse
import random
import sys

PRESETS = {
    '1k': dict(floors=2, rooms_x=2, rooms_z=1, seed=1),
    '4k': dict(floors=2, rooms_x=3, rooms_z=3, seed=2),
    '16k': dict(floors=4, rooms_x=5, rooms_z=4, seed=3),
    '64k': dict(floors=8, rooms_x=7, rooms_z=7, seed=4),
}

STOREY = 3.0          # floor to floor
SLAB = 0.2            # slab thickness: clear height 2.8 m
T_EXT = 0.2           # exterior wall thickness
T_INT = 0.12          # interior wall thickness
DOOR_W, DOOR_H = 0.9, 2.1
WIN_SILL, WIN_TOP = 0.9, 2.2
STAIR_W, STAIR_RISERS, STAIR_RUN = 1.0, 15, 0.25

MATERIALS = '''# Materials of the generated building. Kd = diffuse reflectance,
# Ks/Ns = glossy Phong lobe, Ke = emitted radiance (W/(m^2 sr)).
newmtl plaster
Kd 0.72 0.71 0.68
newmtl ceiling
Kd 0.80 0.80 0.78
newmtl facade
Kd 0.55 0.50 0.45
newmtl concrete
Kd 0.45 0.45 0.43
newmtl floor_wood
Kd 0.45 0.33 0.22
Ks 0.06 0.06 0.06
Ns 40
newmtl floor_tile
Kd 0.60 0.60 0.62
Ks 0.10 0.10 0.10
Ns 80
newmtl stair
Kd 0.50 0.48 0.45
newmtl wood
Kd 0.55 0.38 0.22
Ks 0.08 0.08 0.08
Ns 60
newmtl metal
Kd 0.20 0.20 0.22
Ks 0.40 0.40 0.40
Ns 100
newmtl fabric_blue
Kd 0.12 0.20 0.45
newmtl fabric_red
Kd 0.55 0.12 0.10
newmtl shelf
Kd 0.50 0.44 0.38
newmtl cabinet
Kd 0.62 0.62 0.58
newmtl lamp_frame
Kd 0.80 0.80 0.80
newmtl lamp_panel
Kd 0.80 0.80 0.80
Ke 20 19 17
newmtl lamp_shade
Kd 0.80 0.80 0.80
Ke 2 1.8 1.5
newmtl lamp_bulb
Kd 0.80 0.80 0.80
Ke 30 27 21
'''


DAYLIGHT_SKY = (4.0, 4.3, 5.0)   # an overcast sky, a little blue, W/(m^2 sr)
DAYLIGHT_MATERIALS = '''newmtl glass
Kd 0 0 0
Ks 0.08 0.08 0.08
Ns 2000
Tf 0.85 0.87 0.86
illum 4
newmtl ground
Kd 0.24 0.22 0.18
'''


def daylight_materials():
    """The materials by day: lamps off, glass and the ground added."""
    lines = [l for l in MATERIALS.split('\n') if not l.startswith('Ke ')]
    lines[1] = '# Ks/Ns = glossy Phong lobe; by day the lamps are off (no Ke), Tf = glass.'
    return '\n'.join(lines) + DAYLIGHT_MATERIALS


def box_faces(lo, hi):
    """The six faces of an axis-aligned box, counter-clockwise seen from outside."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    return {
        '-x': [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],
        '+x': [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],
        '-y': [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
        '+y': [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],
        '-z': [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)],
        '+z': [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
    }


class Mesh:
    """Positions and triangles grouped by object name and material."""

    def __init__(self):
        self.verts = []
        self.lines = []
        self.triangles = 0
        self.group_key = None

    def group(self, name, material):
        if self.group_key != (name, material):
            self.lines.append('o %s' % name)
            self.lines.append('usemtl %s' % material)
            self.group_key = (name, material)

    def quad(self, p):
        """A planar convex quadrilateral as two triangles, counter-clockwise."""
        base = len(self.verts)
        self.verts.extend(p)
        a, b, c, d = (base + i + 1 for i in range(4))
        self.lines.append('f %d %d %d' % (a, b, c))
        self.lines.append('f %d %d %d' % (a, c, d))
        self.triangles += 2

    def box(self, lo, hi, skip=()):
        """An axis-aligned solid as up to six faces facing out, each two
        triangles. skip names faces to leave out ('-x', '+x', ...): faces lying
        flat against another surface, or between boxes of one solid."""
        if any(hi[k] - lo[k] <= 1e-6 for k in range(3)):
            return
        faces = box_faces(lo, hi)
        for name in ('-y', '+y', '-x', '+x', '-z', '+z'):
            if name not in skip:
                self.quad(faces[name])

    def face(self, lo, hi, side):
        """One face of a box (used where a face has its own material)."""
        keep = {'-x', '+x', '-y', '+y', '-z', '+z'} - {side}
        self.box(lo, hi, skip=keep)


class Rect:
    def __init__(self, x0, x1, z0, z1):
        self.x0, self.x1, self.z0, self.z1 = x0, x1, z0, z1

    def overlaps(self, o, margin=0.0):
        return (self.x0 < o.x1 + margin and o.x0 < self.x1 + margin and
                self.z0 < o.z1 + margin and o.z0 < self.z1 + margin)

    def inside(self, o):
        return (self.x0 >= o.x0 and self.x1 <= o.x1 and
                self.z0 >= o.z0 and self.z1 <= o.z1)


def fmt(v):
    s = '%.4f' % v
    s = s.rstrip('0').rstrip('.')
    return '0' if s in ('-0', '') else s


class Building:
    def __init__(self, floors, rooms_x, rooms_z, seed, daylight=False):
        self.floors, self.nx, self.nz = floors, rooms_x, rooms_z
        self.daylight = daylight
        self.rng = random.Random(seed)
        self.mesh = Mesh()
        self.layout = []
        # Grid lines: column widths and row depths vary with the seed.
        self.X = [0.0]
        for i in range(rooms_x):
            # The stair column is wide enough for a landing past the top step.
            lo, hi = (5.4, 6.4) if i == 0 else (4.2, 6.0)
            self.X.append(self.X[-1] + round(self.rng.uniform(lo, hi), 2))
        self.Z = [0.0]
        for _ in range(rooms_z):
            self.Z.append(self.Z[-1] + round(self.rng.uniform(3.8, 5.2), 2))
        self.stair_room = (0, 0)

    # --- walls ----------------------------------------------------------------
    def thick_x(self, j):   # wall along x at grid line Z[j]
        return T_EXT if j in (0, self.nz) else T_INT

    def thick_z(self, i):   # wall along z at grid line X[i]
        return T_EXT if i in (0, self.nx) else T_INT

    def room_rect(self, i, j):
        """The floor of room (i, j) between the wall faces."""
        return Rect(self.X[i] + self.thick_z(i) / 2, self.X[i + 1] - self.thick_z(i + 1) / 2,
                    self.Z[j] + self.thick_x(j) / 2, self.Z[j + 1] - self.thick_x(j + 1) / 2)

    def wall(self, axis, c, t, u_lo, u_hi, y0, y1, openings, mat_pos, mat_neg, caps):
        """A wall of thickness t centred on the line where the coordinate
        across it is c ('x': the wall runs along x at z = c; 'z': along z at
        x = c), from u_lo to u_hi along its run and from y0 to y1, cut into
        boxes around its openings (u0, u1, v0, v1): full-height pieces between
        openings, a sill under and a lintel over each. The faces where pieces
        touch each other, the slab or another wall are left out; an opening's
        reveals are faces of their own spanning just the opening. caps: the
        wall's two ends are exposed (a corner of the facade) rather than
        against another wall."""
        m = self.mesh
        if axis == 'x':
            def box(u0, u1, v0, v1):
                return (u0, v0, c - t / 2), (u1, v1, c + t / 2)
            end_lo, end_hi, side_neg, side_pos = '-x', '+x', '-z', '+z'
        else:
            def box(u0, u1, v0, v1):
                return (c - t / 2, v0, u0), (c + t / 2, v1, u1)
            end_lo, end_hi, side_neg, side_pos = '-z', '+z', '-x', '+x'

        def piece(u0, u1, v0, v1, skip):
            lo, hi = box(u0, u1, v0, v1)
            m.group('walls', mat_neg)
            m.box(lo, hi, skip=skip | {side_pos})
            m.group('walls', mat_pos)
            m.face(lo, hi, side_pos)

        openings = sorted(openings)
        prev = u_lo
        for (o0, o1, v0, v1) in openings + [(u_hi, u_hi, None, None)]:
            if o0 > prev + 1e-9:
                skip = {'-y', '+y'}
                if not (prev == u_lo and caps):
                    skip.add(end_lo)
                if not (o0 == u_hi and caps):
                    skip.add(end_hi)
                piece(prev, o0, y0, y1, skip)
            if v0 is None:
                break
            if v0 > y0:
                piece(o0, o1, y0, v0, {'-y', end_lo, end_hi})
            if v1 < y1:
                piece(o0, o1, v1, y1, {'+y', end_lo, end_hi})
            # Reveals: the ends of the pieces beside the opening, over its height.
            m.group('walls', mat_neg)
            lo, hi = box(o0 - t, o0, v0, v1)
            m.face(lo, hi, end_hi)
            lo, hi = box(o1, o1 + t, v0, v1)
            m.face(lo, hi, end_lo)
            prev = o1

    # --- the stair --------------------------------------------------------------
    # The flight of storey s climbs toward +x in one of two bands along the
    # stair room's north wall: band 0 against the wall on even storeys, band
    # 1 beside it on odd ones, so a flight never stands on the hole that the
    # flight below it climbs through.
    def stair_rect(self, s):
        r = self.room_rect(*self.stair_room)
        z0 = r.z0 + (0.0 if s % 2 == 0 else STAIR_W + 0.1)
        x0 = r.x0 + 0.9
        return Rect(x0, x0 + (STAIR_RISERS - 1) * STAIR_RUN, z0, z0 + STAIR_W)

    def hole_rect(self, s):
        """The hole in the slab under storey s, over the flight of storey s-1:
        headroom over its upper steps, ending where its last step meets the
        floor of storey s."""
        st = self.stair_rect(s - 1)
        return Rect(st.x0 + 3 * STAIR_RUN, st.x1, st.z0, st.z1)

    def has_stair(self, s):
        return s < self.floors - 1

    def has_hole(self, s):
        return 0 < s < self.floors

    def stair_zone(self, s):
        """The part of the stair room that the flight of storey s, the hole in
        its floor and their balustrades and approaches occupy (doors, windows
        and furniture keep out of it)."""
        r = self.room_rect(*self.stair_room)
        zs = []
        if self.has_stair(s):
            zs.append(self.stair_rect(s))
        if self.has_hole(s):
            zs.append(self.hole_rect(s))
        if not zs:
            return None
        return Rect(r.x0, r.x1, r.z0, max(z.z1 for z in zs) + 0.6)

    def staircase(self, s):
        m = self.mesh
        st = self.stair_rect(s)
        y0 = s * STOREY
        rise = STOREY / STAIR_RISERS
        against_wall = (s % 2 == 0)
        m.group('stair', 'stair')
        steps = STAIR_RISERS - 1
        for k in range(steps):
            xa, xb = st.x0 + k * STAIR_RUN, st.x0 + (k + 1) * STAIR_RUN
            top = y0 + (k + 1) * rise
            # One solid block per step from the floor up to its tread. The
            # faces between blocks are left out; the face toward the lower step
            # shows as the riser above it. The last block's back faces the room
            # under the upper slab; the floor of the storey above, at the hole's
            # far edge, is the final riser.
            skip = {'-y'}
            if against_wall:
                skip.add('-z')
            if k > 0:
                skip.add('-x')
            if k < steps - 1:
                skip.add('+x')
            m.box((xa, y0, st.z0), (xb, top, st.z1), skip=skip)
            if k > 0:
                m.face((xa, top - rise, st.z0), (xb, top, st.z1), '-x')
        self.layout.append('stair %d %s' % (s, ' '.join(fmt(v) for v in
                                                      (st.x0, st.x1, y0, y0 + STOREY, st.z0, st.z1))))

    def balustrade(self, s):
        """A low rail wall along the open sides of the hole in the floor of
        storey s (not the side against the wall, not the stair's arrival)."""
        m = self.mesh
        h = self.hole_rect(s)
        r = self.room_rect(*self.stair_room)
        y0, y1, t = s * STOREY, s * STOREY + 0.9, 0.05
        m.group('balustrade', 'metal')
        walled = h.z0 <= r.z0 + 1e-9
        z_lo = h.z0 if walled else h.z0 - t
        m.box((h.x0 - t, y0, z_lo), (h.x0, y1, h.z1 + t), skip={'-y'} | ({'-z'} if walled else set()))
        m.box((h.x0, y0, h.z1), (h.x1, y1, h.z1 + t), skip={'-y', '-x'})
        if not walled:
            m.box((h.x0, y0, h.z0 - t), (h.x1, y1, h.z0), skip={'-y', '-x'})

    # --- slabs ------------------------------------------------------------------
    def slab(self, s):
        """The slab whose top is the floor of storey s (s = floors: the roof),
        cut into four boxes around the stair hole where it has one."""
        m = self.mesh
        top = s * STOREY
        bot = top - SLAB
        X0, X1 = self.X[0] - T_EXT / 2, self.X[-1] + T_EXT / 2
        Z0, Z1 = self.Z[0] - T_EXT / 2, self.Z[-1] + T_EXT / 2
        top_mat = 'concrete' if s == self.floors else ('floor_tile' if s % 2 else 'floor_wood')
        bot_mat = 'facade' if s == 0 else 'ceiling'
        if self.has_hole(s):
            h = self.hole_rect(s)
            pieces = [((X0, Z0), (X1, h.z0), {'+z'}),
                      ((X0, h.z1), (X1, Z1), {'-z'}),
                      ((X0, h.z0), (h.x0, h.z1), {'-z', '+z'}),
                      ((h.x1, h.z0), (X1, h.z1), {'-z', '+z'})]
        else:
            pieces = [((X0, Z0), (X1, Z1), set())]
        for (ax, az), (bx, bz), skip in pieces:
            if bx - ax <= 1e-9 or bz - az <= 1e-9:
                continue
            lo, hi = (ax, bot, az), (bx, top, bz)
            m.group('slab', 'concrete')
            m.box(lo, hi, skip=skip | {'+y', '-y'})
            m.group('floor', top_mat)
            m.face(lo, hi, '+y')
            m.group('ceiling', bot_mat)
            m.face(lo, hi, '-y')
        if self.has_hole(s):
            # The hole's long sides (the pieces' faces there were left out
            # because they run on under the other pieces).
            m.group('slab', 'concrete')
            m.face((h.x0, bot, Z0), (h.x1, top, h.z0), '+z')
            m.face((h.x0, bot, h.z1), (h.x1, top, Z1), '-z')

    # --- storeys ----------------------------------------------------------------
    def door_span(self, key, a, b):
        """Where along the wall key a door between rooms a and b may go."""
        axis, _ = key
        lo_room = a if (a[0] < b[0] or a[1] < b[1]) else b
        hi_room = b if lo_room is a else a
        ra, rb = self.room_rect(*lo_room), self.room_rect(*hi_room)
        if axis == 'x':
            return max(ra.x0, rb.x0) + 0.35, min(ra.x1, rb.x1) - 0.35
        lo, hi = max(ra.z0, rb.z0) + 0.35, min(ra.z1, rb.z1) - 0.35
        if self.stair_room in (lo_room, hi_room):
            lo = max(lo, self.stair_keepout_z() + 0.1)
        return lo, hi

    def stair_keepout_z(self):
        r = self.room_rect(*self.stair_room)
        return max(z.z1 for s in range(self.floors)
                   for z in [self.stair_zone(s)] if z is not None) if self.floors > 1 else r.z0

    def plan_doors(self, s):
        """Doors of storey s: a random spanning tree of its rooms plus about a
        third of the remaining adjacencies; on the ground floor an entrance
        in the south facade."""
        rng = self.rng
        edges = []
        for i in range(self.nx):
            for j in range(self.nz):
                if i + 1 < self.nx:
                    edges.append(((i, j), (i + 1, j)))
                if j + 1 < self.nz:
                    edges.append(((i, j), (i, j + 1)))
        rng.shuffle(edges)
        parent = {}

        def find(a):
            while parent.get(a, a) != a:
                a = parent[a]
            return a
        doors = {}
        for a, b in edges:
            ra, rb = find(a), find(b)
            if ra == rb and rng.random() >= 0.35:
                continue
            parent[ra] = rb
            key = ('z', b[0]) if a[0] != b[0] else ('x', b[1])
            lo, hi = self.door_span(key, a, b)
            if hi - lo < DOOR_W:
                continue
            u0 = round(rng.uniform(lo, hi - DOOR_W), 2)
            doors.setdefault(key, []).append((u0, u0 + DOOR_W, 0.0, DOOR_H))
        if s == 0:
            r = self.room_rect(self.nx // 2, self.nz - 1)
            u0 = round((r.x0 + r.x1) / 2 - DOOR_W / 2, 2)
            doors.setdefault(('x', self.nz), []).append((u0, u0 + DOOR_W, 0.0, DOOR_H))
        return doors

    def plan_windows(self, s, doors):
        """Windows in the exterior walls of every room, away from its doors and
        from the stair."""
        rng = self.rng
        wins = {}
        for i in range(self.nx):
            for j in range(self.nz):
                r = self.room_rect(i, j)
                stair = (i, j) == self.stair_room and self.floors > 1
                sides = []
                if j == 0 and not stair:
                    sides.append((('x', 0), r.x0, r.x1))
                if j == self.nz - 1:
                    sides.append((('x', self.nz), r.x0, r.x1))
                if i == 0:
                    sides.append((('z', 0), self.stair_keepout_z() + 0.1 if stair else r.z0, r.z1))
                if i == self.nx - 1:
                    sides.append((('z', self.nx), r.z0, r.z1))
                for key, a, b in sides:
                    n = 2 if b - a > 4.6 else 1
                    w = round(rng.uniform(1.0, 1.5), 2)
                    slot = (b - a) / n
                    if slot < w + 0.4:
                        continue
                    for k in range(n):
                        u0 = round(a + slot * k + (slot - w) / 2, 2)
                        cand = (u0, u0 + w, WIN_SILL, WIN_TOP)
                        clash = any(o[0] < cand[1] + 0.2 and cand[0] < o[1] + 0.2
                                    for o in doors.get(key, []))
                        if not clash:
                            wins.setdefault(key, []).append(cand)
        return wins

    def storey_walls(self, s, doors, wins):
        y0 = s * STOREY
        y1 = y0 + STOREY - SLAB

        def absolute(ops):
            return [(u0, u1, y0 + v0, y0 + v1) for (u0, u1, v0, v1) in ops]
        for j in range(self.nz + 1):          # walls along x, through the crossings
            t = self.thick_x(j)
            ops = absolute(doors.get(('x', j), []) + wins.get(('x', j), []))
            if j in (0, self.nz):
                lo, hi = self.X[0] - T_EXT / 2, self.X[-1] + T_EXT / 2
                mpos, mneg = ('plaster', 'facade') if j == 0 else ('facade', 'plaster')
                self.wall('x', self.Z[j], t, lo, hi, y0, y1, ops, mpos, mneg, caps=True)
            else:
                lo, hi = self.X[0] + T_EXT / 2, self.X[-1] - T_EXT / 2
                self.wall('x', self.Z[j], t, lo, hi, y0, y1, ops, 'plaster', 'plaster', caps=False)
        for i in range(self.nx + 1):          # walls along z, between the x walls
            t = self.thick_z(i)
            ops = absolute(doors.get(('z', i), []) + wins.get(('z', i), []))
            if i in (0, self.nx):
                mpos, mneg = ('plaster', 'facade') if i == 0 else ('facade', 'plaster')
                lo, hi = self.Z[0] + T_EXT / 2, self.Z[-1] - T_EXT / 2
                self.wall('z', self.X[i], t, lo, hi, y0, y1, ops, mpos, mneg, caps=False)
            else:
                for j in range(self.nz):
                    lo = self.Z[j] + self.thick_x(j) / 2
                    hi = self.Z[j + 1] - self.thick_x(j + 1) / 2
                    mine = [o for o in ops if o[0] >= lo and o[1] <= hi]
                    self.wall('z', self.X[i], t, lo, hi, y0, y1, mine, 'plaster', 'plaster', caps=False)
        for kind, table in (('door', doors), ('window', wins)):
            for (axis, g), ops in sorted(table.items()):
                for (u0, u1, v0, v1) in ops:
                    if axis == 'x':
                        t = self.thick_x(g)
                        box = (u0, u1, y0 + v0, y0 + v1, self.Z[g] - t / 2, self.Z[g] + t / 2)
                    else:
                        t = self.thick_z(g)
                        box = (self.X[g] - t / 2, self.X[g] + t / 2, y0 + v0, y0 + v1, u0, u1)
                    self.layout.append('%s %d %s' % (kind, s, ' '.join(fmt(v) for v in box)))
                    if kind == 'window' and self.daylight:
                        self.pane(axis, g, box)

    def pane(self, axis, g, box):
        """By day: the glass of a window, one face across the opening in the
        middle of the wall, facing out of the building."""
        x0, x1, y0, y1, z0, z1 = box
        if axis == 'x':
            c = (z0 + z1) / 2
            lo, hi, side = (x0, y0, c), (x1, y1, c), '-z' if g == 0 else '+z'
        else:
            c = (x0 + x1) / 2
            lo, hi, side = (c, y0, z0), (c, y1, z1), '-x' if g == 0 else '+x'
        self.mesh.group('window', 'glass')
        self.mesh.quad(box_faces(lo, hi)[side])

    def ground(self):
        """By day: the ground round the building at the bottom of the ground
        slab, as wide as the building on each side (four strips: none under
        the building, where it would lie against the slab)."""
        X0, X1 = self.X[0] - T_EXT / 2, self.X[-1] + T_EXT / 2
        Z0, Z1 = self.Z[0] - T_EXT / 2, self.Z[-1] + T_EXT / 2
        w, y = max(X1 - X0, Z1 - Z0), -SLAB
        self.mesh.group('ground', 'ground')
        for (ax, az), (bx, bz) in (((X0 - w, Z0 - w), (X1 + w, Z0)), ((X0 - w, Z1), (X1 + w, Z1 + w)),
                                   ((X0 - w, Z0), (X0, Z1)), ((X1, Z0), (X1 + w, Z1))):
            self.mesh.quad(box_faces((ax, y, az), (bx, y, bz))['+y'])

    # --- furniture -----------------------------------------------------------
    def keepouts(self, s, i, j, doors, wins):
        """Floor areas of room (i, j) that furniture leaves free: a square in
        front of each door, a strip in front of each window (tall furniture
        would close it), the stair."""
        out = []
        for (axis, g), ops in doors.items():
            for (u0, u1, _, _) in ops:
                if axis == 'x':
                    out.append(Rect(u0 - 0.2, u1 + 0.2, self.Z[g] - 1.2, self.Z[g] + 1.2))
                else:
                    out.append(Rect(self.X[g] - 1.2, self.X[g] + 1.2, u0 - 0.2, u1 + 0.2))
        for (axis, g), ops in wins.items():
            for (u0, u1, _, _) in ops:
                if axis == 'x':
                    out.append(Rect(u0 - 0.1, u1 + 0.1, self.Z[g] - 0.7, self.Z[g] + 0.7))
                else:
                    out.append(Rect(self.X[g] - 0.7, self.X[g] + 0.7, u0 - 0.1, u1 + 0.1))
        if (i, j) == self.stair_room:
            z = self.stair_zone(s)
            if z is not None:
                out.append(z)
        return out

    def furnish(self, s, i, j, doors, wins):
        """Desks with chairs by floor area, shelves and a cabinet against the
        walls; returns the desks' rectangles (for desk lamps)."""
        rng = self.rng
        r = self.room_rect(i, j)
        y0 = s * STOREY
        taken = self.keepouts(s, i, j, doors, wins)

        def place(w, d, against_wall, tries=40):
            for _ in range(tries):
                side = None
                if against_wall:
                    side = rng.choice(('-x', '+x', '-z', '+z'))
                    if side in ('-z', '+z'):
                        x = rng.uniform(r.x0, r.x1 - w)
                        z = r.z0 if side == '-z' else r.z1 - d
                        rect = Rect(x, x + w, z, z + d)
                    else:
                        z = rng.uniform(r.z0, r.z1 - w)
                        x = r.x0 if side == '-x' else r.x1 - d
                        rect = Rect(x, x + d, z, z + w)
                else:
                    x = rng.uniform(r.x0 + 0.3, r.x1 - w - 0.3)
                    z = rng.uniform(r.z0 + 0.3, r.z1 - d - 0.3)
                    rect = Rect(x, x + w, z, z + d)
                if rect.inside(r) and not any(rect.overlaps(o, 0.05) for o in taken):
                    taken.append(rect)
                    return rect, side
            return None

        area = (r.x1 - r.x0) * (r.z1 - r.z0)
        desks = []
        for _ in range(max(1, int(area / 12.0))):
            got = place(1.4, 1.5, against_wall=False)
            if got:
                self.desk(got[0], y0)
                desks.append(got[0])
        for _ in range(1 + int(area / 26.0)):
            got = place(0.9, 0.35, against_wall=True)
            if got:
                self.shelf(got[0], got[1], y0)
        if rng.random() < 0.7:
            got = place(0.8, 0.5, against_wall=True)
            if got:
                self.cabinet(got[0], got[1], y0)
        return desks

    def desk(self, rect, y0):
        """A desk (a top on two side panels) in the far 0.75 m of rect, a chair
        (a seat on a column, and a back) in front of it."""
        m = self.mesh
        dx0, dx1 = rect.x0, rect.x1
        dz0, dz1 = rect.z0, rect.z0 + 0.75
        m.group('desk', 'wood')
        m.box((dx0, y0 + 0.72, dz0), (dx1, y0 + 0.75, dz1))
        m.group('desk_side', 'metal')
        for lx in (dx0, dx1 - 0.03):
            m.box((lx, y0, dz0 + 0.05), (lx + 0.03, y0 + 0.72, dz1 - 0.05), skip={'-y', '+y'})
        cx, cz, seat = (dx0 + dx1) / 2 - 0.23, dz1 + 0.25, 0.46
        m.group('chair', 'fabric_blue' if self.rng.random() < 0.5 else 'fabric_red')
        m.box((cx, y0 + 0.44, cz), (cx + seat, y0 + 0.48, cz + seat))
        m.box((cx, y0 + 0.48, cz + seat - 0.04), (cx + seat, y0 + 0.95, cz + seat), skip={'-y'})
        m.group('chair_leg', 'metal')
        c = seat / 2 - 0.025
        m.box((cx + c, y0, cz + c), (cx + c + 0.05, y0 + 0.44, cz + c + 0.05), skip={'-y', '+y'})

    def shelf(self, rect, side, y0):
        """Two side boards and five shelf boards, the back against the wall on
        side."""
        m = self.mesh
        h, b = 1.9, 0.025
        m.group('shelf', 'shelf')
        if side in ('-z', '+z'):
            sides = [Rect(rect.x0, rect.x0 + b, rect.z0, rect.z1), Rect(rect.x1 - b, rect.x1, rect.z0, rect.z1)]
            inner, ends = Rect(rect.x0 + b, rect.x1 - b, rect.z0, rect.z1), {'-x', '+x'}
        else:
            sides = [Rect(rect.x0, rect.x1, rect.z0, rect.z0 + b), Rect(rect.x0, rect.x1, rect.z1 - b, rect.z1)]
            inner, ends = Rect(rect.x0, rect.x1, rect.z0 + b, rect.z1 - b), {'-z', '+z'}
        for sd in sides:
            m.box((sd.x0, y0, sd.z0), (sd.x1, y0 + h, sd.z1), skip={'-y', side})
        for k in range(5):
            y = y0 + 0.08 + k * 0.44
            m.box((inner.x0, y, inner.z0), (inner.x1, y + b, inner.z1), skip=ends | {side})

    def cabinet(self, rect, side, y0):
        m = self.mesh
        m.group('cabinet', 'cabinet')
        m.box((rect.x0, y0, rect.z0), (rect.x1, y0 + 1.0, rect.z1), skip={'-y', side})

    # --- lamps -------------------------------------------------------------
    def light(self, s, i, j, kind, desks):
        """A ceiling panel, a pendant or a desk lamp in room (i, j); returns the
        kind placed (a desk lamp needs a desk, else the room gets a panel)."""
        m = self.mesh
        r = self.room_rect(i, j)
        ceil = s * STOREY + STOREY - SLAB
        cx, cz = (r.x0 + r.x1) / 2, (r.z0 + r.z1) / 2
        if (i, j) == self.stair_room:
            z = self.stair_zone(s)
            if z is not None:
                cz = max(cz, min(z.z1 + 0.4, r.z1 - 0.5))
        if kind == 'desk' and not desks:
            kind = 'panel'
        if kind == 'panel':
            lo, hi = (cx - 0.3, ceil - 0.03, cz - 0.3), (cx + 0.3, ceil, cz + 0.3)
            m.group('lamp_panel', 'lamp_frame')
            m.box(lo, hi, skip={'+y', '-y'})
            m.group('lamp_panel', 'lamp_panel')
            m.face(lo, hi, '-y')
            at = (cx, ceil - 0.03, cz)
        elif kind == 'pendant':
            m.group('lamp_pendant', 'metal')
            m.box((cx - 0.01, ceil - 0.6, cz - 0.01), (cx + 0.01, ceil, cz + 0.01), skip={'+y', '-y'})
            lo, hi = (cx - 0.2, ceil - 0.85, cz - 0.2), (cx + 0.2, ceil - 0.6, cz + 0.2)
            m.group('lamp_pendant', 'lamp_shade')
            m.box(lo, hi, skip={'-y'})
            m.group('lamp_pendant', 'lamp_bulb')
            m.face(lo, hi, '-y')
            at = (cx, ceil - 0.85, cz)
        else:
            d = desks[0]
            x, z, y = d.x0 + 0.15, d.z0 + 0.15, s * STOREY + 0.75
            m.group('lamp_desk', 'metal')
            m.box((x, y, z), (x + 0.03, y + 0.4, z + 0.03), skip={'-y', '+y'})
            lo, hi = (x - 0.08, y + 0.4, z - 0.08), (x + 0.11, y + 0.52, z + 0.11)
            m.group('lamp_desk', 'lamp_shade')
            m.box(lo, hi, skip={'-y'})
            m.group('lamp_desk', 'lamp_bulb')
            m.face(lo, hi, '-y')
            at = ((lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2)
        self.layout.append('lamp %d %d %d %s %s' % (s, i, j, ' '.join(fmt(v) for v in at), kind))
        return kind

    # --- the whole building ------------------------------------------------
    def build(self):
        rng = self.rng
        rooms = [(s, i, j) for s in range(self.floors) for i in range(self.nx) for j in range(self.nz)]
        # Dark rooms (no lamp of their own): about one in twelve, at least one
        # from 4 rooms up, never the stair room.
        candidates = [r for r in rooms if (r[1], r[2]) != self.stair_room]
        dark = set()
        if len(rooms) >= 4 and candidates:
            dark.add(candidates[rng.randrange(len(candidates))])
            dark.update(c for c in candidates if rng.random() < 0.08)
        for s in range(self.floors + 1):
            self.slab(s)
        if self.daylight:
            self.ground()
        room_lines = []
        for s in range(self.floors):
            doors = self.plan_doors(s)
            wins = self.plan_windows(s, doors)
            self.storey_walls(s, doors, wins)
            if self.has_stair(s):
                self.staircase(s)
            if self.has_hole(s):
                self.balustrade(s)
            for i in range(self.nx):
                for j in range(self.nz):
                    desks = self.furnish(s, i, j, doors, wins)
                    if (s, i, j) in dark:
                        kind = 'none'
                    else:
                        u = rng.random()
                        kind = self.light(s, i, j, 'panel' if u < 0.7 else ('pendant' if u < 0.9 else 'desk'), desks)
                    r = self.room_rect(i, j)
                    y0 = s * STOREY
                    stair = 1 if (i, j) == self.stair_room and self.has_stair(s) else 0
                    room_lines.append('room %d %d %d %s %s %d' % (
                        s, i, j, ' '.join(fmt(v) for v in (r.x0, r.x1, y0, y0 + STOREY - SLAB, r.z0, r.z1)),
                        kind, stair))
        sky = ['sky %s' % ' '.join(fmt(v) for v in DAYLIGHT_SKY)] if self.daylight else []
        self.layout = sky + room_lines + self.layout

    def write(self, stem):
        name = stem.split('/')[-1]
        m = self.mesh
        with open(stem + '.obj', 'w') as f:
            f.write('# Generated building, written by make_building.py (%d storeys of %d x %d rooms).\n'
                    % (self.floors, self.nx, self.nz))
            f.write('# Metres, +y up, %d triangles. Layout in %s.layout.\n' % (m.triangles, name))
            if self.daylight:
                f.write('# By day: glass in the windows, lamps off, a ground; the sky is in the layout.\n')
            f.write('mtllib %s.mtl\n' % name)
            for v in m.verts:
                f.write('v %s %s %s\n' % tuple(fmt(c) for c in v))
            f.write('\n'.join(m.lines) + '\n')
        with open(stem + '.mtl', 'w') as f:
            f.write(daylight_materials() if self.daylight else MATERIALS)
        with open(stem + '.layout', 'w') as f:
            f.write('# Layout of %s.obj: see make_building.py for the line formats.\n' % name)
            f.write('\n'.join(self.layout) + '\n')


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--preset', choices=sorted(PRESETS), help='1k, 4k, 16k or 64k triangles')
    ap.add_argument('--floors', type=int)
    ap.add_argument('--rooms-x', type=int)
    ap.add_argument('--rooms-z', type=int)
    ap.add_argument('--seed', type=int)
    ap.add_argument('--daylight', action='store_true',
                    help='by day: glass in the windows, lamps off, a ground and a sky (see above)')
    ap.add_argument('--out', help='output path without extension (default building_<preset>[_daylight] or building)')
    a = ap.parse_args(argv)
    p = dict(PRESETS[a.preset]) if a.preset else dict(floors=2, rooms_x=3, rooms_z=2, seed=1)
    for k in ('floors', 'rooms_x', 'rooms_z', 'seed'):
        if getattr(a, k) is not None:
            p[k] = getattr(a, k)
    if p['floors'] < 1 or p['rooms_x'] < 1 or p['rooms_z'] < 1:
        ap.error('floors, rooms-x and rooms-z must be at least 1')
    if p['floors'] * p['rooms_x'] * p['rooms_z'] > 4096:
        ap.error('at most 4096 rooms')
    b = Building(p['floors'], p['rooms_x'], p['rooms_z'], p['seed'], a.daylight)
    b.build()
    out = a.out or (('building_' + a.preset if a.preset else 'building') + ('_daylight' if a.daylight else ''))
    b.write(out)
    print('%s.obj: %d storeys of %d x %d rooms, %d triangles%s' %
          (out, p['floors'], p['rooms_x'], p['rooms_z'], b.mesh.triangles, ', by day' if a.daylight else ''))


if __name__ == '__main__':
    main(sys.argv[1:])
