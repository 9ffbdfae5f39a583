# A simulated handheld phone capture for measuring `nerfpt poses` (docs/benchmarks.md, "Poses as accurate as
# before the speed-up"): an object on a textured table in a room, props on the table around it, the camera
# walked once around the object at arm's length with hand shake (slow drifts of height, distance and aim, and a
# small roll), portrait frames, rendered with Cycles. Unlike the e2e turntable (tests/e2e/turntable_scene.h) the
# camera does not look exactly at one point, the orbit is not a circle, and most of the features lie on the
# table, the props and the walls rather than on the object.
#
#   blender -b --factory-startup --python scripts/make_handheld_capture.py -- OUT_DIR
#           [--frames 100] [--width 540] [--height 960] [--fov-y 60] [--samples 4] [--seed 1] [--masks 1]
#           [--kind vase|bottle|stack] [--only 2,27,52]
#
# Writes OUT_DIR/render/frame_NNNNN.png (existing frames are skipped, so an interrupted run resumes) and
# OUT_DIR/truth.json (transforms.json layout: fl_x/fl_y/cx/cy/w/h and, per frame, the OpenGL camera-to-world
# matrix, which is Blender's camera matrix_world; 'object': the subject's up, supporting plane height, base
# centre, height and bounding box in Blender's world, metres) and, unless --masks 0, OUT_DIR/masks/frame_NNNNN.png:
# the object's coverage in each frame (RGBA, alpha = coverage; everything else a holdout). To make it a video as a phone would and keep every frame:
#   ffmpeg -framerate 30 -i OUT_DIR/render/frame_%05d.png -c:v libx264 -crf 18 -pix_fmt yuv420p OUT_DIR/handheld.mp4
#   nerfpt curate OUT_DIR/handheld.mp4 -o OUT_DIR/frames --target-frames N
# (curate numbers frames from 0 as the video does, so truth.json's names match; scripts/bench_poses.sh does this.)
# The seed picks the object, the props' places and the shake, so two seeds give two different captures; the
# object's kind is the seed's first draw (seeds 7, 11, 12, 13 are all bottles) unless --kind names it.
# --only renders just the listed frame indices: with --samples 256 --masks 0 into another OUT_DIR, clean references
# of a capture's held-out frames, free of the 4-sample noise (bench/capture_noise_ceiling.py compares them).
import bpy, sys, os, math, json, random
from mathutils import Vector, Matrix, Euler

argv = sys.argv[sys.argv.index('--') + 1:] if '--' in sys.argv else []
if not argv:
    sys.exit('usage: blender -b --factory-startup --python make_handheld_capture.py -- OUT_DIR [--frames N] ...')
out_dir = os.path.abspath(argv[0])
opts = {'frames': 100, 'width': 540, 'height': 960, 'fov-y': 60.0, 'samples': 4, 'seed': 1, 'masks': 1, 'kind': '',
        'only': ''}
i = 1
while i < len(argv):
    key = argv[i].lstrip('-')
    if key not in opts or i + 1 >= len(argv):
        sys.exit(f'make_handheld_capture: unknown option or missing value: {argv[i]}')
    opts[key] = type(opts[key])(argv[i + 1])
    i += 2
rng = random.Random(opts['seed'])

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def material(name, kind, colour_a, colour_b, scale, roughness=0.6):
    """A procedural texture that SIFT can find corners in, as real wood grain, fabric and print have."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    bsdf = nodes['Principled BSDF']
    bsdf.inputs['Roughness'].default_value = roughness
    coord = nodes.new('ShaderNodeTexCoord')
    ramp = nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (*colour_a, 1)
    ramp.color_ramp.elements[1].color = (*colour_b, 1)
    if kind == 'wood':
        tex = nodes.new('ShaderNodeTexWave')
        tex.inputs['Scale'].default_value = scale
        tex.inputs['Distortion'].default_value = 8.0
        tex.inputs['Detail'].default_value = 6.0
    elif kind == 'voronoi':
        tex = nodes.new('ShaderNodeTexVoronoi')
        tex.inputs['Scale'].default_value = scale
    elif kind == 'brick':
        tex = nodes.new('ShaderNodeTexBrick')
        tex.inputs['Scale'].default_value = scale
    elif kind == 'checker':
        tex = nodes.new('ShaderNodeTexChecker')
        tex.inputs['Scale'].default_value = scale
    else:
        tex = nodes.new('ShaderNodeTexNoise')
        tex.inputs['Scale'].default_value = scale
        tex.inputs['Detail'].default_value = 8.0
    links.new(coord.outputs['Object'], tex.inputs['Vector'])
    links.new(tex.outputs['Fac' if 'Fac' in tex.outputs else 'Distance'], ramp.inputs['Fac'])
    links.new(ramp.outputs['Color'], bsdf.inputs['Base Color'])
    return m


def add(obj_op, location, scale, mat, rotation=(0, 0, 0), **kw):
    obj_op(location=location, rotation=rotation, **kw)
    o = bpy.context.active_object
    o.scale = scale
    o.data.materials.append(mat)
    return o


cube = bpy.ops.mesh.primitive_cube_add
cyl = bpy.ops.mesh.primitive_cylinder_add
sphere = bpy.ops.mesh.primitive_uv_sphere_add

# Room: floor, four walls with a print-like texture, a ceiling light. Table top at z = 0.75.
add(cube, (0, 0, -0.05), (3.5, 3.5, 0.05), material('floor', 'brick', (0.25, 0.2, 0.15), (0.5, 0.45, 0.4), 40))
wall = material('wall', 'voronoi', (0.7, 0.65, 0.55), (0.2, 0.25, 0.35), 40)
for x, y, sx, sy in ((3.5, 0, 0.05, 3.5), (-3.5, 0, 0.05, 3.5), (0, 3.5, 3.5, 0.05), (0, -3.5, 3.5, 0.05)):
    add(cube, (x, y, 1.4), (sx, sy, 1.4), wall)
top_z = 0.75
wood = material('wood', 'wood', (0.12, 0.06, 0.03), (0.45, 0.28, 0.14), 12, roughness=0.4)
add(cube, (0, 0, top_z - 0.02), (0.7, 0.45, 0.02), wood)
for x in (-0.65, 0.65):
    for y in (-0.4, 0.4):
        add(cube, (x, y, (top_z - 0.04) / 2), (0.03, 0.03, (top_z - 0.04) / 2), wood)
# A sun through a window and a sky's fill: direct light that a few samples per pixel render with little noise.
bpy.ops.object.light_add(type='SUN', location=(0, 0, 3), rotation=(math.radians(35), 0, math.radians(30)))
bpy.context.active_object.data.energy = 3.0
bpy.context.active_object.data.angle = math.radians(3)
scene.world = bpy.data.worlds.new('world')
scene.world.use_nodes = True
scene.world.node_tree.nodes['Background'].inputs['Strength'].default_value = 2.0

# The object: a vase, a bottle or a figure of primitives, with its own texture, at the table's centre.
kinds = ['vase', 'bottle', 'stack']
kind = rng.choice(kinds)  # drawn even when --kind names one, so that a seed keeps the rest of its scene
if opts['kind']:
    if opts['kind'] not in kinds:
        sys.exit(f"make_handheld_capture: --kind {opts['kind']}: expected one of {', '.join(kinds)}")
    kind = opts['kind']
obj_mat = material('object', rng.choice(['noise', 'voronoi', 'checker']),
                   (rng.random(), rng.random(), rng.random()), (rng.random(), rng.random(), rng.random()),
                   rng.uniform(3, 8), roughness=0.3)
parts = []  # the object's meshes: its ground truth (box, height) is their bounding box
if kind == 'vase':
    parts.append(add(cyl, (0, 0, top_z + 0.1), (0.07, 0.07, 0.1), obj_mat))
    parts.append(add(sphere, (0, 0, top_z + 0.2), (0.09, 0.09, 0.07), obj_mat))
elif kind == 'bottle':
    parts.append(add(cyl, (0, 0, top_z + 0.09), (0.045, 0.045, 0.09), obj_mat))
    parts.append(add(cyl, (0, 0, top_z + 0.22), (0.015, 0.015, 0.04), obj_mat))
    parts.append(add(sphere, (0, 0, top_z + 0.18), (0.045, 0.045, 0.03), obj_mat))
else:
    parts.append(add(cube, (0, 0, top_z + 0.05), (0.08, 0.06, 0.05), obj_mat, rotation=(0, 0, 0.3)))
    parts.append(add(sphere, (0, 0, top_z + 0.16), (0.06, 0.06, 0.06), obj_mat))
object_centre = Vector((0, 0, top_z + 0.12))

# Props on the table around the object (books, a cup, a ball), none on the camera's path.
prop_kinds = ['book', 'cup', 'ball', 'book', 'box']
for k, prop in enumerate(prop_kinds):
    angle = 2 * math.pi * (k + rng.uniform(-0.3, 0.3)) / len(prop_kinds)
    r = rng.uniform(0.25, 0.38)
    x, y = r * math.cos(angle), max(-0.38, min(0.38, r * math.sin(angle)))
    m = material(f'prop{k}', rng.choice(['noise', 'voronoi', 'brick', 'checker']),
                 (rng.random(), rng.random(), rng.random()), (rng.random(), rng.random(), rng.random()),
                 rng.uniform(5, 15))
    if prop == 'book':
        add(cube, (x, y, top_z + 0.02), (0.1, 0.07, 0.02), m, rotation=(0, 0, rng.uniform(0, math.pi)))
    elif prop == 'cup':
        add(cyl, (x, y, top_z + 0.05), (0.04, 0.04, 0.05), m)
    elif prop == 'ball':
        add(sphere, (x, y, top_z + 0.04), (0.04, 0.04, 0.04), m)
    else:
        add(cube, (x, y, top_z + 0.04), (0.05, 0.05, 0.04), m, rotation=(0, 0, rng.uniform(0, math.pi)))

# Camera: one walk around the object. Hand shake as a sum of a few slow sines of random phase (a person's
# height, distance and aim drift over seconds) plus a small per-frame tremor.
W, H, N = opts['width'], opts['height'], opts['frames']
bpy.ops.object.camera_add()
cam = bpy.context.active_object
scene.camera = cam
cam.data.sensor_fit = 'VERTICAL'
cam.data.angle_y = math.radians(opts['fov-y'])


def drift(amplitude):
    waves = [(rng.uniform(1, 4), rng.uniform(0, 2 * math.pi)) for _ in range(3)]
    return lambda t: amplitude * sum(math.sin(2 * math.pi * f * t + p) for f, p in waves) / len(waves)


radius, height, aim_x, aim_y, aim_z, roll = drift(0.08), drift(0.07), drift(0.04), drift(0.04), drift(0.03), drift(2.5)
start = rng.uniform(0, 2 * math.pi)
poses = []
for k in range(N):
    t = k / N
    a = start + 2 * math.pi * t
    r = 0.9 + radius(t)
    eye = Vector((r * math.cos(a), r * math.sin(a), top_z + 0.35 + height(t)))
    eye += Vector((rng.gauss(0, 0.003), rng.gauss(0, 0.003), rng.gauss(0, 0.003)))
    target = object_centre + Vector((aim_x(t), aim_y(t), aim_z(t)))
    look = (target - eye).normalized()
    rot = look.to_track_quat('-Z', 'Y').to_matrix().to_4x4()
    roll_deg = roll(t) + rng.gauss(0, 0.3)
    rot = rot @ Matrix.Rotation(math.radians(roll_deg), 4, 'Z')
    poses.append(Matrix.Translation(eye) @ rot)

scene.render.engine = 'CYCLES'
scene.cycles.device = 'CPU'
scene.cycles.samples = opts['samples']
scene.cycles.max_bounces = 0  # sun and sky only: a third of the cost of one bounce, corners as sharp
# Debian's Blender has no denoiser; the remaining sample noise stands in for the phone's sensor noise (the video
# encoder then smooths it as a phone's does).
scene.cycles.use_denoising = False
scene.cycles.seed = opts['seed']
scene.render.resolution_x, scene.render.resolution_y = W, H
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = 'PNG'
scene.render.image_settings.color_mode = 'RGB'
scene.view_settings.view_transform = 'Standard'

os.makedirs(os.path.join(out_dir, 'render'), exist_ok=True)
fy = 0.5 * H / math.tan(0.5 * math.radians(opts['fov-y']))
truth = {'fl_x': fy, 'fl_y': fy, 'cx': 0.5 * W, 'cy': 0.5 * H, 'w': W, 'h': H, 'frames': []}
for k, m in enumerate(poses):
    name = f'frame_{k:05d}.png'
    truth['frames'].append({'file_path': name, 'transform_matrix': [list(row) for row in m]})
# The object's ground truth in Blender's world (Z up, metres): what `nerfpt capture` should find (issue 25).
bpy.context.view_layer.update()
corners = [o.matrix_world @ Vector(c) for o in parts for c in o.bound_box]
lo = [min(c[a] for c in corners) for a in range(3)]
hi = [max(c[a] for c in corners) for a in range(3)]
truth['object'] = {'kind': kind, 'up': [0, 0, 1], 'plane_z': top_z,
                   'base_center': [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), top_z],
                   'height': hi[2] - top_z, 'box_min': lo, 'box_max': hi}
with open(os.path.join(out_dir, 'truth.json'), 'w') as f:
    json.dump(truth, f, indent=1)


only = {int(x) for x in opts['only'].split(',') if x.strip()}
if any(k < 0 or k >= N for k in only):
    sys.exit(f'make_handheld_capture: --only names a frame outside 0..{N - 1}: {opts["only"]}')


def render_poses(folder, what):
    """Every pose (or those --only names) to OUT_DIR/FOLDER/frame_NNNNN.png; existing files are skipped, so a run
    resumes."""
    os.makedirs(os.path.join(out_dir, folder), exist_ok=True)
    for k, m in enumerate(poses):
        if only and k not in only:
            continue
        path = os.path.join(out_dir, folder, f'frame_{k:05d}.png')
        if os.path.exists(path):
            continue
        cam.matrix_world = m
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        print(f'make_handheld_capture: {what} {k + 1} of {N}', flush=True)


render_poses('render', 'frame')
# The object's ground-truth masks (issue 25): the same cameras with everything but the object a holdout and the
# film transparent, so alpha is the object's coverage (anti-aliased over the samples); written as 8-bit RGBA
# OUT_DIR/masks/frame_NNNNN.png, named as the frames so that `nerfpt eval --masks OUT_DIR/masks` finds them.
if opts['masks']:
    object_names = {o.name for o in parts}
    for o in scene.objects:
        if o.type == 'MESH' and o.name not in object_names:
            o.is_holdout = True
    scene.render.film_transparent = True
    scene.cycles.samples = 16
    scene.render.image_settings.color_mode = 'RGBA'
    render_poses('masks', 'mask')
print(f'make_handheld_capture: {N} frames of {W}x{H} ({kind}) in {out_dir}')
