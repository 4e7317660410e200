# cycles_scene.py — renders a tessera scene (JSON, format v1) with Blender Cycles, for the
# comparison of bench/cycles/run.sh (bench/README.md, "Against Blender Cycles").
#
#   blender -b --factory-startup -noaudio --python-exit-code 1 -P cycles_scene.py -- \
#       --scene scenes/cornell-box.json --spp 64 --out out.exr [--width W] [--threads 2] \
#       [--seed S] [--max-depth D] [--bounces-offset K] [--warmup]
#   blender ... -P cycles_scene.py -- --check-units --out probe.exr
#   blender ... -P cycles_scene.py -- --scene SCENE.json --width W --write-scene OUT.json
#
# --check-units renders an emitter of radiance (0.5, 0.25, 2) filling a 16×16 view (every
# pixel must read exactly that). --write-scene writes the scene with its film resized to
# --width (height keeps the aspect) and renders nothing: the document tessera renders in
# the comparison, so both renderers read the same file.
#
# Design note: the translation covers what the Cornell box uses and refuses everything else
# with a message (so a scene it cannot reproduce is never silently rendered differently):
# a perspective pinhole camera, a box pixel filter, the path integrator, `diffuse`
# materials without Oren–Nayar, `mesh` shapes given inline (positions + indices, no
# transform), emission on meshes, no separate lights. Geometry keeps the scene's
# coordinates (Cycles has no up axis; only the camera's frame matters).
#
# Correspondences (each checked by run.sh: --check-units, and the converged images):
# - Radiance: an Emission closure of colour c and strength s on a mesh has radiance c·s in
#   Cycles, as tessera's `emission`; a Diffuse BSDF of colour ρ and roughness 0 is
#   Lambertian with albedo ρ. Colours are written as scene-linear (Rec.709) values.
# - Camera: tessera's fov is the full angle along the shorter image axis (as pbrt), so the
#   Blender sensor is fitted along that axis. right = forward × up (docs/design.md §4).
# - Depth: tessera's max_depth D (pbrt-v3: up to D scattering events, light sampled at
#   each) is Cycles' max_bounces D − 1: Cycles counts bounces after the first hit (0 =
#   direct light only; Blender adds one internally). --bounces-offset changes the "− 1".
# - Pixel filter: box of radius r pixels = Cycles' BOX of width 2r.
# - No denoiser, no adaptive sampling, no clamping, light threshold 0, no glossy blur, no
#   path guiding; Cycles' default sampling pattern (progressive multi-jitter in 3.4) and
#   Russian roulette, which it cannot switch off. View transform Standard; the EXR is
#   linear float32 whatever the view transform.
#
# Time: perf_counter around bpy.ops.render.render (scene sync, BVH build, sampling, film
# read-out; not Blender's start-up nor the EXR write). --warmup first renders 1 spp so the
# timed render does not pay one-time initialisation. Prints one line
#   CYCLES_RESULT {"spp": …, "seconds": …, "width": …, "height": …, "max_bounces": …}
import json
import math
import os
import sys
import time

import bpy
from mathutils import Matrix, Vector


def fail(msg):
    print("cycles_scene: " + msg, file=sys.stderr)
    sys.exit(1)


def parse_args(argv):
    args = {"scene": None, "spp": 16, "out": None, "width": 0, "threads": 2, "seed": 0,
            "max_depth": 0, "bounces_offset": -1, "warmup": False, "check_units": False,
            "write_scene": None}
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("--warmup", "--check-units"):
            args[a[2:].replace("-", "_")] = True
            i += 1
            continue
        if i + 1 >= len(argv):
            fail("missing value after " + a)
        v = argv[i + 1]
        key = a[2:].replace("-", "_")
        if key not in args:
            fail("unknown option " + a)
        args[key] = v if key in ("scene", "out", "write_scene") else int(v)
        i += 2
    if not args["out"] and not args["write_scene"]:
        fail("--out OUT.exr is required")
    return args


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for mat in list(bpy.data.materials):
        bpy.data.materials.remove(mat)


def black_world(scene):
    world = bpy.data.worlds.new("black") if scene.world is None else scene.world
    world.use_nodes = True
    bg = world.node_tree.nodes.get("Background")
    bg.inputs["Color"].default_value = (0, 0, 0, 1)
    bg.inputs["Strength"].default_value = 0.0
    scene.world = world


def setup_cycles(scene, width, height, spp, threads, seed, max_bounces, filter_width):
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.film_transparent = False
    r.threads_mode = "FIXED"
    r.threads = threads
    r.use_persistent_data = False
    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.time_limit = 0.0
    c.seed = seed
    c.use_animated_seed = False
    c.sample_offset = 0
    c.max_bounces = max_bounces
    c.diffuse_bounces = max_bounces
    c.glossy_bounces = max_bounces
    c.transmission_bounces = max_bounces
    c.volume_bounces = 0
    c.transparent_max_bounces = max_bounces
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.use_fast_gi = False
    c.use_guiding = False
    c.pixel_filter_type = "BOX"
    c.filter_width = filter_width
    c.film_exposure = 1.0
    scene.view_layers[0].cycles.denoising_store_passes = False
    scene.view_layers[0].cycles.use_denoising = False
    vs = scene.view_settings
    vs.view_transform = "Standard"
    vs.look = "None"
    vs.exposure = 0.0
    vs.gamma = 1.0
    settings = r.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGB"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"


def diffuse_material(name, rgb):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (rgb[0], rgb[1], rgb[2], 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat


def emission_material(name, rgb, reflectance):
    if any(x != 0 for x in reflectance):
        fail(name + ": emitters with a non-black diffuse reflectance are not translated")
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    em = nodes.new("ShaderNodeEmission")
    strength = max(rgb)
    em.inputs["Color"].default_value = tuple(x / strength for x in rgb) + (1.0,)
    em.inputs["Strength"].default_value = strength
    mat.node_tree.links.new(em.outputs["Emission"], out.inputs["Surface"])
    return mat


def add_mesh(name, positions, indices, material):
    verts = [tuple(positions[i:i + 3]) for i in range(0, len(positions), 3)]
    faces = [tuple(indices[i:i + 3]) for i in range(0, len(indices), 3)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_camera(scene, eye, target, up, fov_deg, width, height):
    eye, target, up = Vector(eye), Vector(target), Vector(up)
    forward = (target - eye).normalized()
    right = forward.cross(up).normalized()
    cam_up = right.cross(forward)
    # Blender cameras look down their local −Z with local +Y up.
    rot = Matrix((right, cam_up, -forward)).transposed()
    data = bpy.data.cameras.new("camera")
    data.type = "PERSP"
    data.lens_unit = "FOV"
    # fov is along the shorter axis; Cycles applies angle to the fitted sensor axis.
    data.sensor_fit = "VERTICAL" if width >= height else "HORIZONTAL"
    data.angle = math.radians(fov_deg)
    data.shift_x = data.shift_y = 0.0
    dist = (target - eye).length
    data.clip_start = dist * 1e-4
    data.clip_end = dist * 1e3
    obj = bpy.data.objects.new("camera", data)
    obj.matrix_world = Matrix.Translation(eye) @ rot.to_4x4()
    scene.collection.objects.link(obj)
    scene.camera = obj


def build_from_json(scene, path, args):
    with open(path) as f:
        doc = json.load(f)
    if doc.get("lights"):
        fail("separate lights are not translated (the script covers emissive meshes)")
    cam = doc["camera"]
    if cam.get("type", "perspective") != "perspective" or cam.get("lens_radius", 0) != 0:
        fail("camera: only a perspective pinhole camera is translated")
    film = doc["film"]
    width, height = film["width"], film["height"]
    if args["width"]:
        height = max(1, round(height * args["width"] / width))
        width = args["width"]
    if film.get("crop"):
        fail("film.crop is not translated")
    filt = film.get("filter", {"type": "box", "radius": 0.5})
    if filt.get("type") != "box":
        fail("film.filter: only the box filter is translated exactly (got %s)" % filt.get("type"))
    integ = doc.get("integrator", {})
    if integ.get("type", "path") != "path":
        fail("integrator: only path is translated")
    max_depth = args["max_depth"] or integ.get("max_depth", 5)
    max_bounces = max_depth + args["bounces_offset"]
    if max_bounces < 0:
        fail("max_depth + bounces_offset must be ≥ 0")

    mats = {}
    for name, m in doc["materials"].items():
        if m.get("type") != "diffuse" or m.get("sigma", 0) != 0:
            fail("materials.%s: only Lambertian diffuse is translated" % name)
        mats[name] = m.get("reflectance", [0.5, 0.5, 0.5])
    for i, s in enumerate(doc["shapes"]):
        where = "shapes[%d]" % i
        if s.get("type") != "mesh" or "positions" not in s or s.get("transform"):
            fail(where + ": only inline meshes without transform are translated")
        refl = mats[s["material"]]
        if "emission" in s:
            mat = emission_material("emit%d" % i, s["emission"], refl)
        else:
            mat = bpy.data.materials.get(s["material"]) or diffuse_material(s["material"], refl)
        add_mesh("shape%d" % i, s["positions"], s["indices"], mat)
    add_camera(scene, cam["from"], cam["to"], cam.get("up", [0, 1, 0]), cam["fov"], width, height)
    return width, height, max_bounces, 2.0 * filt.get("radius", 0.5)


def build_units_probe(scene):
    """An emitter filling the view: a big quad of radiance (0.5, 0.25, 2.0), facing the camera."""
    em = emission_material("probe", [0.5, 0.25, 2.0], [0, 0, 0])
    add_mesh("probe", [-10, -10, 0, 10, -10, 0, 10, 10, 0, -10, 10, 0], [0, 1, 2, 0, 2, 3], em)
    add_camera(scene, [0, 0, 5], [0, 0, 0], [0, 1, 0], 30.0, 16, 16)
    return 16, 16, 0, 1.0


def write_scene(args):
    if not args["scene"]:
        fail("--scene SCENE.json is required")
    with open(args["scene"]) as f:
        doc = json.load(f)
    film = doc["film"]
    if args["width"]:
        film["height"] = max(1, round(film["height"] * args["width"] / film["width"]))
        film["width"] = args["width"]
    with open(args["write_scene"], "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args = parse_args(argv)
    if args["write_scene"]:
        write_scene(args)
        return
    scene = bpy.context.scene
    clear_scene()
    black_world(scene)
    if args["check_units"]:
        width, height, max_bounces, fw = build_units_probe(scene)
        args["spp"] = 4
    else:
        if not args["scene"]:
            fail("--scene SCENE.json is required")
        width, height, max_bounces, fw = build_from_json(scene, args["scene"], args)
    setup_cycles(scene, width, height, args["spp"], args["threads"], args["seed"], max_bounces, fw)
    if args["warmup"]:
        scene.cycles.samples = 1
        bpy.ops.render.render()
        scene.cycles.samples = args["spp"]
    t0 = time.perf_counter()
    bpy.ops.render.render()
    seconds = time.perf_counter() - t0
    out = os.path.abspath(args["out"])
    bpy.data.images["Render Result"].save_render(filepath=out, scene=scene)
    if not os.path.exists(out):
        fail("Blender did not write " + out)
    print("CYCLES_RESULT " + json.dumps({"spp": args["spp"], "seconds": seconds, "width": width,
                                         "height": height, "max_bounces": max_bounces,
                                         "threads": args["threads"], "seed": args["seed"],
                                         "blender": bpy.app.version_string}))


main()
