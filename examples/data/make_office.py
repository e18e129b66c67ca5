#!/usr/bin/env python3
"""Writes office.obj and office.mtl: the project's office scene, about sixty
quadrilaterals like the office of Hardt's radiosity thesis and Greger's
irradiance-volume walkthrough. Units are metres, +y is up.

Room 5 x 2.8 x 4 m. A desk near the back wall with space under it (the bunny
walks under it), a floor lamp beside it whose shade emits (strongly upward, a
halogen uplight, so most of the room is lit from the ceiling), a yellow divider
(colour bleeding), shelves on the left wall and three paintings.

Every quadrilateral is planar and convex and winds counter-clockwise seen
from the side it faces. Boxes omit faces that lie on the floor or a wall.
Run `python3 make_office.py` in this folder to regenerate the files."""

verts, lines = [], []

def quad(p):
    base = len(verts)
    verts.extend(p)
    lines.append('f %d %d %d %d' % tuple(base + i + 1 for i in range(4)))

def box(lo, hi, skip=(), inward=False):
    """Axis-aligned box as up to six quads facing out (or in, for the room).
    skip names faces to omit: '-x', '+x', '-y', '+y', '-z', '+z'."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    faces = {
        '-x': [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],
        '+x': [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],
        '-y': [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
        '+y': [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],
        '-z': [(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)],
        '+z': [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
    }
    for name in ('-y', '+y', '-x', '+x', '-z', '+z'):
        if name in skip:
            continue
        f = faces[name]
        quad(f[::-1] if inward else f)

def group(name, material):
    lines.append('o ' + name)
    lines.append('usemtl ' + material)

# Room: floor, ceiling and four walls, facing inward.
group('floor', 'floor');        box((0, 0, 0), (5, 2.8, 4), skip=('+y', '-x', '+x', '-z', '+z'), inward=True)
group('ceiling', 'ceiling');    box((0, 0, 0), (5, 2.8, 4), skip=('-y', '-x', '+x', '-z', '+z'), inward=True)
group('walls', 'wall');         box((0, 0, 0), (5, 2.8, 4), skip=('-y', '+y'), inward=True)

# Desk: a top slab on two side panels, open in the middle.
group('desk', 'wood')
box((1.0, 0.72, 2.9), (2.6, 0.75, 3.7))
box((1.0, 0.0, 2.9), (1.03, 0.72, 3.7), skip=('-y', '+y'))
box((2.57, 0.0, 2.9), (2.6, 0.72, 3.7), skip=('-y', '+y'))

# Floor lamp right of the desk: a pole and an emitting shade.
group('lamp_pole', 'metal');    box((3.28, 0.0, 3.38), (3.32, 1.6, 3.42), skip=('-y', '+y'))
group('lamp_shade_top', 'lamp_up');     box((3.12, 1.6, 3.22), (3.48, 1.85, 3.58), skip=('-y', '-x', '+x', '-z', '+z'))
group('lamp_shade_side', 'lamp_side');  box((3.12, 1.6, 3.22), (3.48, 1.85, 3.58), skip=('-y', '+y'))
group('lamp_shade_bottom', 'lamp_down'); box((3.12, 1.6, 3.22), (3.48, 1.85, 3.58), skip=('+y', '-x', '+x', '-z', '+z'))

# Divider: a yellow panel standing in the room.
group('divider', 'yellow');     box((3.6, 0.0, 1.3), (3.65, 1.5, 2.6), skip=('-y',))

# Shelves on the left wall: two side boards and three shelf boards.
group('shelves', 'shelf')
box((0.0, 0.0, 1.0), (0.35, 1.8, 1.03), skip=('-y', '-x'))
box((0.0, 0.0, 1.87), (0.35, 1.8, 1.9), skip=('-y', '-x'))
for y in (0.6, 1.2, 1.77):
    box((0.0, y, 1.03), (0.35, y + 0.03, 1.87), skip=('-x', '-z', '+z'))

# Paintings, 1 cm in front of the walls.
group('painting_red', 'paint_red');     quad([(4.99, 1.2, 1.0), (4.99, 1.2, 1.8), (4.99, 1.9, 1.8), (4.99, 1.9, 1.0)])
group('painting_blue', 'paint_blue');   quad([(4.99, 1.1, 2.4), (4.99, 1.1, 3.4), (4.99, 1.8, 3.4), (4.99, 1.8, 2.4)])
group('painting_green', 'paint_green'); quad([(1.2, 1.3, 3.99), (2.4, 1.3, 3.99), (2.4, 2.0, 3.99), (1.2, 2.0, 3.99)][::-1])

with open('office.obj', 'w') as f:
    f.write('# Office scene for the project\'s examples, written by make_office.py.\n')
    f.write('# Metres, +y up, %d quadrilaterals. See make_office.py for the layout.\n' % sum(l.startswith('f ') for l in lines))
    f.write('mtllib office.mtl\n')
    for v in verts:
        f.write('v %g %g %g\n' % v)
    f.write('\n'.join(lines) + '\n')

with open('office.mtl', 'w') as f:
    f.write('''# Office materials. Kd = diffuse reflectance, Ks/Ns = glossy Phong lobe,
# Ke = emitted radiance (W/(m^2 sr)).
newmtl floor
Kd 0.42 0.33 0.24
Ks 0.08 0.08 0.08
Ns 40
newmtl ceiling
Kd 0.80 0.80 0.78
newmtl wall
Kd 0.70 0.70 0.66
newmtl wood
Kd 0.55 0.38 0.22
Ks 0.10 0.10 0.10
Ns 60
newmtl metal
Kd 0.20 0.20 0.20
Ks 0.40 0.40 0.40
Ns 100
newmtl lamp_up
Kd 0.80 0.80 0.80
Ke 40 36 28
newmtl lamp_side
Kd 0.80 0.80 0.80
Ke 6 5.4 4.2
newmtl lamp_down
Kd 0.80 0.80 0.80
Ke 12 10.8 8.4
newmtl yellow
Kd 0.75 0.62 0.12
newmtl shelf
Kd 0.50 0.44 0.38
newmtl paint_red
Kd 0.70 0.15 0.10
newmtl paint_blue
Kd 0.10 0.20 0.60
newmtl paint_green
Kd 0.15 0.50 0.20
''')
