"""Unit tests of the add-on's modules that need no Blender (plain python3): reading nerfpt's output, the
child process and its cancel, the model file header and placement, the glTF additions (area lights, the specular layer), the main-thread queue.

python3 tests/blender/test_pure.py BUILD_DIR   (BUILD_DIR/nerfpt is used where a real binary is needed)
"""

import json
import math
import os
import stat
import struct
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "blender"))
from nerfpt_blender import area_lights, child_process, gltf_post, main_thread, model_file, nerfpt_cli  # noqa: E402

BUILD = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else ""


def write(path, data):
    with open(path, "wb") as f:
        f.write(data)


def script(folder, name, body):
    p = os.path.join(folder, name)
    with open(p, "w") as f:
        f.write("#!/bin/sh\n" + body + "\n")
    os.chmod(p, os.stat(p).st_mode | stat.S_IXUSR)
    return p


class CliOutput(unittest.TestCase):
    def test_version(self):
        self.assertEqual(nerfpt_cli.parse_version("nerfpt 0.1.0\n"), (0, 1, 0))
        self.assertEqual(nerfpt_cli.parse_version("nerfpt 12.3.45-dirty"), (12, 3, 45))
        self.assertIsNone(nerfpt_cli.parse_version("blender 3.4.1"))
        self.assertIsNone(nerfpt_cli.parse_version(""))

    def test_progress_and_messages(self):
        self.assertEqual(nerfpt_cli.progress_fraction("render: 40% (1.2M samples/s, ETA 3.0 s)"), 0.4)
        self.assertEqual(nerfpt_cli.progress_fraction("bake: 100% (2.0M voxels/s, 1.0 s)"), 1.0)
        self.assertIsNone(nerfpt_cli.progress_fraction("nerfpt: info: rendering 80x60"))
        self.assertEqual(
            nerfpt_cli.error_message("nerfpt: error: m.npt: file not found"), "m.npt: file not found"
        )
        self.assertEqual(nerfpt_cli.warning_message("nerfpt: warning: x"), "x")
        self.assertIsNone(nerfpt_cli.error_message("render: 10%"))

    def test_failure_message(self):
        lines = ["render: 10% (...)", "nerfpt: error: scene.gltf: bad", "render: 20% (...)"]
        self.assertEqual(nerfpt_cli.failure_message(lines, 1), "scene.gltf: bad")
        self.assertEqual(
            nerfpt_cli.failure_message(["render: 10% (x)", "Segmentation fault"], 139), "Segmentation fault"
        )
        self.assertEqual(nerfpt_cli.failure_message([], -9), "nerfpt was killed by signal 9")
        self.assertEqual(nerfpt_cli.failure_message([], 3), "nerfpt exited with code 3")

    def test_ignored_report_lists_each_thing_once(self):
        self.assertIsNone(nerfpt_cli.ignored_report([], []))
        gltf = "/tmp/nerfpt-render-x/scene.gltf"
        report = nerfpt_cli.ignored_report(
            ["area light 'a' is not exported", "motion blur is ignored", "area light 'a' is not exported"],
            [f"{gltf}: mesh 'edges': primitive mode 1 is not TRIANGLES", f"{gltf}: mesh 'edges': primitive mode 1 "
             "is not TRIANGLES", "motion blur is ignored"],
            gltf,
        )
        self.assertEqual(
            report,
            "nerfpt ignores: area light 'a' is not exported; motion blur is ignored; nerfpt: scene: mesh 'edges': "
            "primitive mode 1 is not TRIANGLES; nerfpt: motion blur is ignored",
        )
        self.assertEqual(nerfpt_cli.ignored_report(["x"]), "nerfpt ignores: x")

    def test_find_and_check_binary(self):
        with tempfile.TemporaryDirectory() as d:
            with self.assertRaisesRegex(nerfpt_cli.NerfptError, "does not exist"):
                nerfpt_cli.find_binary(os.path.join(d, "nope"))
            old = script(d, "old", "echo 'nerfpt 0.0.1'")
            self.assertEqual(nerfpt_cli.find_binary(old), old)
            with self.assertRaisesRegex(nerfpt_cli.NerfptError, "too old"):
                nerfpt_cli.check_version(old)
            slow = script(d, "slow", "sleep 5")
            with self.assertRaisesRegex(nerfpt_cli.NerfptError, "did not answer"):
                nerfpt_cli.check_version(slow, timeout=0.5)
            build = os.path.join(d, "build")
            os.mkdir(build)
            fake = script(build, "nerfpt", "echo 'nerfpt 9.9.9'")
            saved = os.environ["PATH"]
            os.environ["PATH"] = "/nonexistent"
            try:
                self.assertEqual(nerfpt_cli.find_binary("", [build]), fake)
                with self.assertRaisesRegex(nerfpt_cli.NerfptError, "not found .*PATH"):
                    nerfpt_cli.find_binary("", [d])
            finally:
                os.environ["PATH"] = saved
            self.assertEqual(nerfpt_cli.check_version(fake), (9, 9, 9))

    @unittest.skipUnless(BUILD and os.path.isfile(os.path.join(BUILD, "nerfpt")), "no built nerfpt")
    def test_real_binary(self):
        self.assertGreaterEqual(
            nerfpt_cli.check_version(os.path.join(BUILD, "nerfpt")), nerfpt_cli.MIN_VERSION
        )


class Child(unittest.TestCase):
    def test_lines_progress_and_exit_code(self):
        cmd = ["sh", "-c", "echo out1; echo 'render: 50% (x)' >&2; echo 'nerfpt: warning: w' >&2; "
               "echo 'nerfpt: error: it broke' >&2; exit 1"]  # fmt: skip
        seen = []
        child = child_process.run(cmd, on_line=lambda c, s, line: seen.append((s, line)))
        self.assertEqual(child.returncode, 1)
        self.assertFalse(child.cancelled)
        self.assertEqual(child.progress, 0.5)
        self.assertEqual(child.stdout_lines, ["out1"])
        self.assertEqual(child.failure(), "it broke")
        self.assertEqual(child.warnings(), ["w"])
        self.assertIn(("out", "out1"), seen)

    def test_lines_taken_by_cancel_reach_on_line(self):
        # The loop's first look comes at the start, while the child sleeps; its line comes 0.2 s later, before
        # should_cancel answers (0.8 s), so cancel() takes it from the pipe; on_line must still see it (it once
        # saw only what the loop itself had polled).
        seen = []
        child = child_process.run(["sh", "-c", "sleep 0.2; echo out1; sleep 5"],
                                  should_cancel=lambda c: time.sleep(0.8) or True,
                                  on_line=lambda c, s, line: seen.append((s, line)))
        self.assertTrue(child.cancelled)
        self.assertEqual(child.stdout_lines, ["out1"])
        self.assertEqual(seen, [("out", "out1")])

    def test_cancel_stops_at_once(self):
        t0 = time.time()
        child = child_process.run(["sleep", "30"], should_cancel=lambda c: time.time() - t0 > 0.3)
        self.assertTrue(child.cancelled)
        self.assertLess(time.time() - t0, 5)
        self.assertFalse(child_process.process_exists(child.pid))

    def test_cancel_kills_what_ignores_sigterm(self):
        t0 = time.time()
        ignores = "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); time.sleep(30)"
        with child_process.ChildProcess([sys.executable, "-c", ignores]) as child:
            time.sleep(0.2)
            child.cancel(grace_s=0.5)
        self.assertTrue(child.cancelled)
        self.assertLess(time.time() - t0, 5)
        self.assertFalse(child_process.process_exists(child.pid))

    def test_missing_program(self):
        with self.assertRaisesRegex(nerfpt_cli.NerfptError, "cannot start"):
            child_process.ChildProcess(["/nonexistent/nerfpt"])


def write_model(path, aabb_scale, scale, offset, extra_sections=()):
    """A minimal file with the sections placement() reads (the rest of a real model is not needed)."""
    m = [
        0,
        scale,
        0,
        offset[1],
        0,
        0,
        scale,
        offset[2],
        scale,
        0,
        0,
        offset[0],
        0,
        0,
        0,
        1,
    ]  # ngp_world_to_model
    body = b""
    for tag, payload in (*extra_sections, (b"SCEN", struct.pack("<f16d", aabb_scale, *m))):
        body += tag + struct.pack("<Q", len(payload)) + payload
    with open(path, "wb") as f:
        f.write(b"NPTNERF1" + struct.pack("<I", 1) + body)


class ModelFile(unittest.TestCase):
    def test_placement(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "m.npt")
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"CONF", b"{}" * 1000)])
            place = model_file.placement(p)
            for a in range(3):
                self.assertAlmostEqual(place["centre"][a], 0.0, places=6)
                self.assertAlmostEqual(place["half_size"][a], 0.5 / 0.33, places=5)
            # Model x, y, z = world y, z, x: a crop longer along model z is longer along world x.
            place = model_file.placement(p, ((0.4, 0.4, 0.2), (0.6, 0.6, 0.8)))
            self.assertAlmostEqual(place["half_size"][0], 0.3 / 0.33, places=5)
            self.assertAlmostEqual(place["half_size"][1], 0.1 / 0.33, places=5)
            self.assertAlmostEqual(place["centre"][0], 0.0, places=6)
            write_model(p, 4.0, 0.25, (0.5, 0.5, 0.5))
            self.assertAlmostEqual(model_file.placement(p)["half_size"][2], 2.0 / 0.25, places=5)

    def test_relightable(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "m.npt")
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"CONF", b"{}")])
            self.assertEqual(model_file.section_tags(p), ["CONF", "SCEN"])
            self.assertFalse(model_file.is_relightable(p))
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"CONF", b"{}"), (b"RLIT", b"x" * 100)])
            self.assertTrue(model_file.is_relightable(p))
            with open(p, "rb") as f:
                data = f.read()
            write(p, data[:40])  # inside RLIT's payload
            with self.assertRaisesRegex(model_file.ModelFileError, "truncated \\(section 'RLIT'\\)"):
                model_file.is_relightable(p)
            write(p, b"hello")
            with self.assertRaisesRegex(model_file.ModelFileError, "not a nerfpt model"):
                model_file.is_relightable(p)

    def test_object_frame(self):
        frame = {
            "version": 1,
            "metric": True,
            "object_to_world": [2, 0, 0, 0.1, 0, 2, 0, 0, 0, 0, 2, -0.5, 0, 0, 0, 1],
            "box": {"min": [-0.2, -0.1, 0], "max": [0.2, 0.1, 0.4]},
        }
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "m.npt")
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5))
            self.assertIsNone(model_file.object_frame(p))
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"OBJF", json.dumps(frame).encode())])
            f = model_file.object_frame(p)
            self.assertTrue(f["metric"])
            self.assertEqual(f["object_to_world"][2], [0, 0, 2, -0.5])
            # World x in [-0.3, 0.5], y in [-0.2, 0.2], z in [-0.5, 0.3]; model = world (y, z, x) * 0.33 + 0.5.
            lo, hi = model_file.object_crop(p, f)
            for a, (want_lo, want_hi) in enumerate(((-0.2, 0.2), (-0.5, 0.3), (-0.3, 0.5))):
                self.assertAlmostEqual(lo[a], want_lo * 0.33 + 0.5, places=6)
                self.assertAlmostEqual(hi[a], want_hi * 0.33 + 0.5, places=6)
            for bad, msg in (
                (b"{", "not an object frame"),
                (json.dumps({**frame, "box": {"min": [0, 0, 0]}}).encode(), "not an object frame"),
                (json.dumps({**frame, "object_to_world": [1] * 15}).encode(), "16 numbers"),
                (json.dumps({**frame, "box": {"min": [0, 0, 1], "max": [1, 1, 1]}}).encode(), "below the maximum"),
            ):
                write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"OBJF", bad)])
                with self.assertRaisesRegex(model_file.ModelFileError, "section 'OBJF': .*" + msg):
                    model_file.object_frame(p)
            far = {**frame, "object_to_world": [2, 0, 0, 50, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1]}
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5), [(b"OBJF", json.dumps(far).encode())])
            with self.assertRaisesRegex(model_file.ModelFileError, "outside the model's box"):
                model_file.object_crop(p, model_file.object_frame(p))

    def test_bad_files(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "m.npt")
            with self.assertRaisesRegex(model_file.ModelFileError, "cannot open"):
                model_file.read_scene_section(p)
            write(p, b"hello")
            with self.assertRaisesRegex(model_file.ModelFileError, "not a nerfpt model"):
                model_file.read_scene_section(p)
            write(p, b"NPTNERF1" + struct.pack("<I", 7))
            with self.assertRaisesRegex(model_file.ModelFileError, "version 7"):
                model_file.read_scene_section(p)
            write(p, b"NPTNERF1" + struct.pack("<I", 1) + b"CONF" + struct.pack("<Q", 2) + b"{}")
            with self.assertRaisesRegex(model_file.ModelFileError, "missing section 'SCEN'"):
                model_file.read_scene_section(p)
            write(p, b"NPTNERF1" + struct.pack("<I", 1) + b"SCEN" + struct.pack("<Q", 132) + b"\0" * 10)
            with self.assertRaisesRegex(model_file.ModelFileError, "truncated"):
                model_file.read_scene_section(p)
            write_model(p, 1.0, 0.33, (0.5, 0.5, 0.5))
            with self.assertRaisesRegex(model_file.ModelFileError, "inside the model's box"):
                model_file.placement(p, ((-0.5, 0, 0), (1, 1, 1)))
            with self.assertRaisesRegex(model_file.ModelFileError, "minimum must be below"):
                model_file.placement(p, ((0.5, 0, 0), (0.5, 1, 1)))

    @unittest.skipUnless(
        BUILD and os.path.isfile(os.path.join(BUILD, "blender_tests", "model", "spheres.npt")), "no model"
    )
    def test_real_model(self):
        place = model_file.placement(os.path.join(BUILD, "blender_tests", "model", "spheres.npt"))
        self.assertAlmostEqual(place["half_size"][0], 0.5 / 0.33, places=5)


class Gltf(unittest.TestCase):
    def test_volume_cube(self):
        g = {"scenes": [{"nodes": [0]}], "nodes": [{"name": "floor"}], "materials": [{"name": "white"}]}
        world = [[2, 0, 0, 1], [0, 2, 0, 2], [0, 0, 2, 3], [0, 0, 0, 1]]
        cube = {"name": "cap", "matrix": gltf_post.gltf_node_matrix(world), "min": [-1, -1, -1], "max": [1, 1, 1],
                "extras": {"volume": {"file": "m.npt"}}}  # fmt: skip
        data = gltf_post.add_volume_cubes(g, [cube, dict(cube, name="cap2")], "v.bin")
        self.assertEqual(len(data), g["buffers"][0]["byteLength"])
        self.assertEqual(g["scenes"][0]["nodes"], [0, 1, 2])
        self.assertEqual(g["materials"][1]["name"], "volume")
        node = g["nodes"][1]
        # Column major; Blender (x, y, z) -> glTF (x, z, -y): translation (1, 3, -2), local y -> glTF -z.
        self.assertEqual(node["matrix"][12:15], [1.0, 3.0, -2.0])
        self.assertEqual(node["matrix"][4:7], [0.0, 0.0, -2.0])
        prim = g["meshes"][node["mesh"]]["primitives"][0]
        self.assertEqual(prim["material"], 1)
        pos = g["accessors"][prim["attributes"]["POSITION"]]
        view = g["bufferViews"][pos["bufferView"]]
        corners = struct.unpack_from("<24f", data, view["byteOffset"])
        self.assertEqual(min(corners), -1.0)
        self.assertEqual(pos["min"], [-1.0, -1.0, -1.0])
        idx = g["accessors"][prim["indices"]]
        iview = g["bufferViews"][idx["bufferView"]]
        tris = struct.unpack_from("<36H", data, iview["byteOffset"])
        self.assertEqual(sorted(set(tris)), list(range(8)))
        self.assertEqual(iview["byteOffset"] % 2, 0)
        self.assertEqual(
            g["bufferViews"][
                g["accessors"][g["meshes"][1]["primitives"][0]["attributes"]["POSITION"]]["bufferView"]
            ]["byteOffset"]
            % 4,
            0,
        )
        json.dumps(g)  # serialisable
        self.assertEqual(gltf_post.add_volume_cubes({}, [], "x.bin"), b"")

    def test_materials_and_extras(self):
        g = {
            "scenes": [{"nodes": []}],
            "materials": [{"name": "m", "doubleSided": True, "pbrMetallicRoughness": {}}],
        }
        gltf_post.replace_material(g, 0, gltf_post.lambert([0.5, 0.25, 0.125, 1.0]))
        m = g["materials"][0]
        self.assertEqual(m["name"], "m")
        self.assertTrue(m["doubleSided"])
        self.assertEqual(m["pbrMetallicRoughness"]["metallicFactor"], 0.0)
        self.assertEqual(m["extensions"]["KHR_materials_specular"]["specularFactor"], 0.0)
        self.assertIn("KHR_materials_specular", g["extensionsUsed"])
        e = gltf_post.emitter([2.0, 1.0, 0.0], 5.0)
        self.assertEqual(e["emissiveFactor"], [1.0, 0.5, 0.0])
        self.assertEqual(e["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"], 10.0)
        gltf_post.set_scene_extras(g, width=8, spp=4)
        self.assertEqual(g["scenes"][0]["extras"], {"width": 8, "spp": 4})

    def test_specular_layer(self):
        """docs/blender.md, "Specular": F0 = 0.08 Specular kept, the layer scaled where Cycles' exact Fresnel of a
        low index reflects less on average than Schlick's."""
        self.assertEqual(gltf_post.cycles_specular_factor(0.0), 0.0)
        for s in (0.3, 0.5, 1.0):
            self.assertEqual(gltf_post.cycles_specular_factor(s), 1.0)
        # Exact Fresnel of eta = 1.0582 (F0 = 0.0008): cosine-weighted average 0.01586, by a finer integral.
        eta, n = (1 + math.sqrt(0.0008)) / (1 - math.sqrt(0.0008)), 100000
        avg = 2 * sum(gltf_post._fresnel_dielectric((i + 0.5) / n, eta) * (i + 0.5) / n for i in range(n)) / n
        sf = gltf_post.cycles_specular_factor(0.01)
        self.assertAlmostEqual(sf, 21 * avg - 20 * 0.0008, places=4)
        self.assertAlmostEqual(sf * (0.0008 / sf + (1 - 0.0008 / sf) / 21), avg, places=4)  # averages agree
        factors = [gltf_post.cycles_specular_factor(i / 100) for i in range(31)]
        self.assertEqual(factors, sorted(factors))  # continuous from 0, increasing
        g = {}
        # Specular 0: the exporter's specularColorFactor 0 alone leaves a full grazing layer; Cycles has none.
        black = {"extensions": {"KHR_materials_specular": {"specularColorFactor": [0.0, 0.0, 0.0]}}}
        gltf_post.cycles_specular_layer(g, black, 0.0, 0.0)
        self.assertEqual(black["extensions"]["KHR_materials_specular"]["specularFactor"], 0.0)
        self.assertIn("KHR_materials_specular", g["extensionsUsed"])
        bare = {}  # no extension written
        gltf_post.cycles_specular_layer(g, bare, 0.0, 0.0)
        self.assertEqual(bare["extensions"]["KHR_materials_specular"], {"specularFactor": 0.0})
        # Specular 0.01: the layer scaled by sf, the colour factor by 1/sf, so F0 = sf x colour stays.
        low = {"extensions": {"KHR_materials_specular": {"specularColorFactor": [0.02, 0.02, 0.01]}}}
        gltf_post.cycles_specular_layer(g, low, 0.01, 0.0)
        ext = low["extensions"]["KHR_materials_specular"]
        self.assertAlmostEqual(ext["specularFactor"], sf)
        self.assertAlmostEqual(ext["specularColorFactor"][2] * sf, 0.01)
        # Glass keeps its own Fresnel: half transmission halves the scaling.
        half = {}
        gltf_post.cycles_specular_layer(g, half, 0.0, 0.5)
        self.assertEqual(half["extensions"]["KHR_materials_specular"]["specularFactor"], 0.5)
        # Specular >= 0.3, full glass, or a linked input: as exported.
        for s, t in ((0.3, 0.0), (1.0, 0.0), (0.0, 1.0), (None, 0.0), (0.0, None)):
            mat = {"extensions": {"KHR_materials_specular": {"specularColorFactor": [0.2, 0.2, 0.2]}}}
            gltf_post.cycles_specular_layer({}, mat, s, t)
            self.assertEqual(mat["extensions"]["KHR_materials_specular"], {"specularColorFactor": [0.2, 0.2, 0.2]})


class AreaLights(unittest.TestCase):
    @staticmethod
    def polygon_area(points):
        n = len(points)
        return 0.5 * sum(points[i][0] * points[(i + 1) % n][1] - points[(i + 1) % n][0] * points[i][1]
                         for i in range(n))  # fmt: skip

    def test_outline_keeps_the_area(self):
        self.assertAlmostEqual(self.polygon_area(area_lights.outline("RECTANGLE", 2.0, 0.5)), 1.0)
        self.assertAlmostEqual(self.polygon_area(area_lights.outline("SQUARE", 2.0, 0.5)), 4.0)
        disc = area_lights.outline("DISK", 2.0, 0.5)
        self.assertEqual(len(disc), area_lights.ROUND_SEGMENTS)
        self.assertAlmostEqual(self.polygon_area(disc), math.pi, places=12)  # counter-clockwise: positive
        self.assertAlmostEqual(self.polygon_area(area_lights.outline("ELLIPSE", 2.0, 0.5, 7)), math.pi / 4, places=12)

    def test_cycles_area_and_radiance(self):
        world = [[2, 0, 0, 1], [0, 3, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
        self.assertAlmostEqual(area_lights.cycles_area("RECTANGLE", 1.0, 0.5, world), 3.0)
        self.assertAlmostEqual(area_lights.cycles_area("DISK", 1.0, 0.5, world), 6.0 * math.pi / 4)
        self.assertAlmostEqual(area_lights.cycles_area("ELLIPSE", 1.0, 0.5, world), 3.0 * math.pi / 4)
        self.assertEqual(area_lights.radiance([1.0, 0.5, 0.0], 100.0, 2.0), [12.5, 6.25, 0.0])

    def check_faces(self, world, down):
        for shape in ("SQUARE", "DISK"):
            pos, tris = area_lights.emitter_mesh(shape, 1.0, 1.0, world)
            for a, b, c in tris:
                e1 = [pos[b][k] - pos[a][k] for k in range(3)]
                e2 = [pos[c][k] - pos[a][k] for k in range(3)]
                nz = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
                self.assertGreater(sum(nz[k] * down[k] for k in range(3)), 0.0, (shape, world))

    def test_faces_the_lights_minus_z(self):
        self.check_faces([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]], [0, 0, -1])
        # Turned to face +x (local z -> world -x), and mirrored (local x -> world -x).
        self.check_faces([[0, 0, -1, 0], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]], [1, 0, 0])
        self.check_faces([[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], [0, 0, -1])

    def test_add_emitters(self):
        g = {"scenes": [{"nodes": [0]}], "nodes": [{"name": "floor"}], "materials": [{"name": "white"}]}
        world = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]]
        lights = [
            {"name": "rect", "shape": "RECTANGLE", "size_x": 2.0, "size_y": 0.5, "world": world,
             "color": [1.0, 0.5, 0.25], "power": 40.0},
            {"name": "disc", "shape": "DISK", "size_x": 1.0, "size_y": 9.0, "world": world,
             "color": [1.0, 1.0, 1.0], "power": math.pi},
        ]  # fmt: skip
        data = area_lights.add_emitters(g, lights, "a.bin")
        self.assertEqual(len(data), g["buffers"][0]["byteLength"])
        self.assertEqual(g["scenes"][0]["nodes"], [0, 1, 2])
        rect, disc = (g["materials"][g["meshes"][g["nodes"][i]["mesh"]]["primitives"][0]["material"]] for i in (1, 2))
        self.assertFalse(rect["doubleSided"])
        strength = rect["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
        self.assertAlmostEqual(strength, 40.0 / (4 * 1.0))  # P / (4 A), colour peak 1
        self.assertEqual(rect["emissiveFactor"], [1.0, 0.5, 0.25])
        self.assertAlmostEqual(disc["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"], 1.0)
        self.assertIn("KHR_materials_emissive_strength", g["extensionsUsed"])
        prim = g["meshes"][g["nodes"][2]["mesh"]]["primitives"][0]
        pos = g["accessors"][prim["attributes"]["POSITION"]]
        self.assertEqual(pos["count"], area_lights.ROUND_SEGMENTS + 1)
        self.assertAlmostEqual(pos["min"][1], 2.0)  # glTF y = Blender z
        idx = g["accessors"][prim["indices"]]
        self.assertEqual(idx["count"], 3 * area_lights.ROUND_SEGMENTS)
        view = g["bufferViews"][idx["bufferView"]]
        tris = struct.unpack_from(f"<{idx['count']}H", data, view["byteOffset"])
        self.assertEqual(max(tris), area_lights.ROUND_SEGMENTS)
        json.dumps(g)
        self.assertEqual(area_lights.add_emitters({}, [], "x.bin"), b"")


class MainThread(unittest.TestCase):
    def test_call_from_another_thread(self):
        results = {}

        def worker():
            results["value"] = main_thread.call(lambda: threading.current_thread() is threading.main_thread())
            try:
                main_thread.call(lambda: 1 / 0)
            except ZeroDivisionError:
                results["raised"] = True

        t = threading.Thread(target=worker)
        t.start()
        while t.is_alive():
            main_thread.drain()  # what the timer does
            time.sleep(0.01)
        self.assertEqual(results, {"value": True, "raised": True})

    def test_main_thread_calls_directly(self):
        self.assertEqual(main_thread.call(lambda: 42), 42)

    def test_cancel_before_start(self):
        results = {}
        t = threading.Thread(
            target=lambda: results.setdefault("r", main_thread.call(lambda: 1, should_cancel=lambda: True))
        )
        t.start()
        t.join(5)
        self.assertFalse(t.is_alive())
        self.assertIsNone(results["r"])
        main_thread.drain()  # the abandoned task is dropped, not run


if __name__ == "__main__":
    unittest.main(verbosity=2)
