# A relighting data set of another object, made exactly as ../shared/data/relight/make_relight.py makes `dev`
# (the same capture light, lightings, cameras' law, Cycles settings, room and file layout), for checking that the
# relight stage's defaults were not fitted to dev (issue 24: the scored object is kept apart).
#
#   blender -b --factory-startup --python scripts/make_relight_object.py -- OUTDIR [--object vase] [make_relight args]
#
# Objects here: `vase` (a rippled glazed vase, a bevelled block, a cell-textured egg and a striped cup on a brick
# slab). Each has its own camera seed, so no camera repeats dev's. The generator itself is the shared one: this
# file only adds objects to it.
import math
import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.environ.get('NERFPT_SHARED', os.path.join(HERE, '..', '..', 'shared'))
GENERATOR = os.path.join(SHARED, 'data', 'relight', 'make_relight.py')
if not os.path.exists(GENERATOR):
    raise SystemExit('make_relight_object: %s not found (set NERFPT_SHARED to the shared folder)' % GENERATOR)

SEEDS = {'vase': 20261207}
argv = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
if argv[-1:] == ['--object']:
    raise SystemExit('make_relight_object: --object needs a name (have: %s)' % ', '.join(SEEDS))
variant = argv[argv.index('--object') + 1] if '--object' in argv else 'vase'
if variant not in SEEDS:
    raise SystemExit('make_relight_object: unknown object %r (have: %s)' % (variant, ', '.join(SEEDS)))
# The shared generator reads its own arguments at import: hand it dev's name (its only seed) and swap after.
rest = [a for i, a in enumerate(argv) if a != '--object' and (i == 0 or argv[i - 1] != '--object')]
sys.argv = [sys.argv[0], '--'] + rest[:1] + ['--object', 'dev'] + rest[1:]
source = open(GENERATOR).read()
body = source[:source.rstrip().rfind('main()')]  # everything but the final call
env = {'__file__': GENERATOR, '__name__': 'make_relight'}
exec(compile(body, GENERATOR, 'exec'), env)


def catmull_rom(points, steps):
    """The points joined by a uniform Catmull-Rom spline, `steps` samples a span (the ends repeated)."""
    p = [points[0]] + list(points) + [points[-1]]
    out = []
    for i in range(1, len(p) - 2):
        for k in range(steps if i < len(p) - 3 else steps + 1):
            t = k / steps
            out.append(tuple(0.5 * (2 * b + (c - a) * t + (2 * a - 5 * b + 4 * c - d) * t * t +
                                    (3 * b - a - 3 * c + d) * t ** 3)
                             for a, b, c, d in zip(p[i - 1], p[i], p[i + 1], p[i + 2])))
    return out


def build_vase():
    """About 2 units tall on z = -1, inside [-1.2, 1.2]^3; dielectrics, roughness 0.3-0.8, object-space textures."""
    textured, plain, cylinder, uvsphere, lathe, added = (env[k] for k in (
        'textured', 'plain', 'cylinder', 'uvsphere', 'lathe', 'added'))
    slab = textured('bricks', 'brick', 3.0, [(0.0, (0.55, 0.22, 0.12)), (1.0, (0.80, 0.74, 0.62))], 0.7,
                    interp='CONSTANT')
    cylinder('slab', 1.05, 1.05, 0.12, slab, seg=4, loc=(0, 0, -0.94), rot=(0, 0, math.radians(45)), smooth=False)
    glaze = textured('glaze', 'noise', 4.0, [(0.4, (0.10, 0.30, 0.40)), (0.6, (0.70, 0.82, 0.80))], 0.3,
                     Detail=4.0)
    # The body through a Catmull-Rom spline, 8 rings a span: a coarse profile under smooth shading would give the
    # truth's normals interpolated across flat bands that a NeRF (rightly) sees flat.
    body = [(0.18, -0.88), (0.30, -0.80), (0.40, -0.55), (0.42, -0.30), (0.34, -0.05), (0.20, 0.20),
            (0.15, 0.40), (0.19, 0.62), (0.26, 0.80)]
    profile = catmull_rom(body, 8) + [(0.001, 0.80)]  # closed by a flat lid
    vase = lathe('vase', profile, glaze, ripple=lambda th, z: 1.0 + 0.06 * math.sin(8 * th) * max(0.0, -z))
    vase.location = (-0.35, 0.2, 0.0)
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(0.45, 0.35, -0.62), rotation=(0, 0, math.radians(30)))
    block = added('block', textured('magic', 'magic', 2.0, [(0.2, (0.85, 0.55, 0.35)), (0.8, (0.25, 0.20, 0.45))],
                                    0.65))
    bev = block.modifiers.new('bevel', 'BEVEL'); bev.width = 0.06; bev.segments = 4
    block.data.use_auto_smooth = True; bev.harden_normals = True  # flat faces stay flat under smooth shading
    uvsphere('egg', 0.24, textured('spots', 'voronoi', 7.0, [(0.0, (0.95, 0.92, 0.80)), (1.0, (0.45, 0.30, 0.20))],
                                   0.55), (0.45, -0.45, -0.62), scale=(1.0, 1.0, 1.35))
    cylinder('cup', 0.2, 0.16, 0.34, textured('bands', 'wave', 6.0, [(0.3, (0.90, 0.90, 0.88)), (0.7, (0.15, 0.35, 0.15))],
                                           0.45), seg=64, loc=(0.55, 0.05, 0.0))
    cylinder('plinth', 0.2, 0.2, 0.45, plain('terracotta', (0.58, 0.30, 0.18), 0.8), loc=(0.55, 0.05, -0.55))


BUILDERS = {'vase': build_vase}
env['build_object'] = lambda _name: BUILDERS[variant]()
env['SEED'] = SEEDS[variant]
env['rng'] = env['random'].Random(SEEDS[variant])
env['OBJECT'] = variant
env['main']()
