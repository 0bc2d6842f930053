# Runs inside Blender (blender -b --factory-startup --python THIS -- JOB.json):
# renders one scene with Cycles under vismask's conventions and writes a
# linear little-endian PFM and an emitter mask PGM. tools/reference writes the
# job file and is the only caller; see its docstring for the conventions.
#
# Job (JSON): vertices [[x,y,z]...], faces [[i,j,k,...]...] (0-based, counter-
# clockwise seen from the front), face_materials [m...], materials
# [{"kd":[r,g,b],"ke":[r,g,b],"two_sided":bool,"camera_only_emission":bool}...],
# area_lamps [{corner, edge1, edge2, ke}...] (AreaLamp), camera {eye,target,up,fovy}, width,
# height, spp, seed, threads (0: all), work (a scratch directory), pfm, pgm
# (the paths to write), mask_dilate (pixels), sky (null, [r,g,b]: a world of
# that radiance, or {file, sha256}: an equirectangular map; unseen by camera
# rays), sun (null or {toward, irradiance,
# degrees}: a Sun lamp of that strength, W/m^2 of irradiance).
import array
import json
import math
import os
import sys
import time

import bpy
from mathutils import Matrix, Vector

# The package's mask dilation, as tools/reference's supersampling uses it
# (Blender's Python has the standard library the package needs).
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from vismask_tools.images import dilated_mask  # noqa: E402


def Fail(msg):
    print("reference-blender: " + msg, file=sys.stderr)
    sys.exit(3)


def ClearScene():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    for coll in (bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras):
        for d in list(coll):
            coll.remove(d)


def MakeMaterial(name, kd, ke, two_sided=False, camera_only_emission=False):
    """Front side: Lambertian diffuse with reflectance kd, plus, when ke > 0, an
    Emission of colour ke/pi and strength 1 (Cycles' emission closure gives
    radiance colour x strength, which the unit-emitter self-test checks: an
    exitance ke is a radiance ke/pi). Back side (Geometry.Backfacing = 1): a
    black diffuse, so a back face absorbs every ray and emits nothing, like a
    vismask patch seen from behind. Two-sided (glTF doubleSided): both sides
    are the front, as a vismask patch and its twin (Cycles' diffuse and
    emission act on whichever side a ray meets). camera_only_emission: the
    emission is seen by camera rays alone and is no light source (an Area
    lamp lights the scene in its place: AreaLamp)."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (kd[0], kd[1], kd[2], 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    front = diffuse.outputs["BSDF"]
    if max(ke) > 0.0:
        emission = nt.nodes.new("ShaderNodeEmission")
        emission.inputs["Color"].default_value = (ke[0] / math.pi, ke[1] / math.pi, ke[2] / math.pi, 1.0)
        emission.inputs["Strength"].default_value = 1.0
        if camera_only_emission:
            path = nt.nodes.new("ShaderNodeLightPath")
            nt.links.new(path.outputs["Is Camera Ray"], emission.inputs["Strength"])
            m.cycles.sample_as_light = False
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(diffuse.outputs["BSDF"], add.inputs[0])
        nt.links.new(emission.outputs["Emission"], add.inputs[1])
        front = add.outputs["Shader"]
    if two_sided:
        nt.links.new(front, out.inputs["Surface"])
        return m
    black = nt.nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(front, mix.inputs[1])
    nt.links.new(black.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return m


def AreaLamp(lamp, scene_diag):
    """A rectangular Area lamp on an emitting rectangle (corner, edge1,
    edge2; counter-clockwise from its front), shining from its front with
    the exitance ke: Cycles gives an Area lamp of power P and area A the
    radiance P / (A pi) * pi / 4 (measured: 0.7852-0.7853 of the exact
    polygon integral everywhere on the Cornell box), so P = max(ke) A 4/pi
    and the colour ke / max(ke). It sits 1e-5 of the scene's diagonal in
    front of the face, so that a shadow ray ending on it does not meet the
    face; it is not seen by camera rays (the face is)."""
    c, e1, e2 = Vector(lamp["corner"]), Vector(lamp["edge1"]), Vector(lamp["edge2"])
    n = e1.cross(e2).normalized()
    k = max(lamp["ke"])
    data = bpy.data.lights.new("area", "AREA")
    data.shape = "RECTANGLE"
    data.size, data.size_y = e1.length, e2.length
    data.energy = k * e1.length * e2.length * 4.0 / math.pi
    data.color = tuple(v / k for v in lamp["ke"])
    data.cycles.cast_shadow = True
    obj = bpy.data.objects.new("area", data)
    x, y, z = e1.normalized(), e2.normalized(), -n  # an Area lamp shines along its local -z
    centre = c + 0.5 * e1 + 0.5 * e2 + n * (1e-5 * scene_diag)
    m = Matrix.Identity(4)
    for i in range(3):
        m[i][0], m[i][1], m[i][2], m[i][3] = x[i], y[i], z[i], centre[i]
    obj.matrix_world = m
    obj.visible_camera = False
    bpy.context.scene.collection.objects.link(obj)


def MakeCamera(cam, scene_diag):
    eye = Vector(cam["eye"])
    f = (Vector(cam["target"]) - eye).normalized()
    r = f.cross(Vector(cam["up"])).normalized()  # image +x (as vismask's MakeView)
    u = r.cross(f)                               # image +y
    data = bpy.data.cameras.new("camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.sensor_height = 24.0
    data.lens = 0.5 * data.sensor_height / math.tan(0.5 * math.radians(cam["fovy"]))
    dist = (Vector(cam["target"]) - eye).length
    data.clip_start = 1e-3 * dist  # vismask's near plane
    data.clip_end = 1e3 * (scene_diag + (eye - Vector(cam["target"])).length)
    obj = bpy.data.objects.new("camera", data)
    m = Matrix.Identity(4)
    for i in range(3):  # Blender's camera looks down its local -z, local +y is up
        m[i][0], m[i][1], m[i][2], m[i][3] = r[i], u[i], -f[i], eye[i]
    obj.matrix_world = m
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj


def Settings(job):
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    c = s.cycles
    c.device = "CPU"
    c.samples = job["spp"]
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = job["seed"]
    c.use_animated_seed = False
    c.max_bounces = 1024
    c.diffuse_bounces = 1024
    c.glossy_bounces = 0
    c.transmission_bounces = 0
    c.volume_bounces = 0
    # A path passes through an Area lamp (AreaLamp) as a transparent bounce:
    # with none allowed it would end there, and what lies behind the lamp
    # (its face, which reflects) would be lost.
    c.transparent_max_bounces = 1024
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0  # never skip a light
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.blur_glossy = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.film_exposure = 1.0
    s.render.film_transparent = False
    s.render.resolution_x = job["width"]
    s.render.resolution_y = job["height"]
    s.render.resolution_percentage = 100
    s.render.pixel_aspect_x = s.render.pixel_aspect_y = 1.0
    s.render.use_border = False
    s.render.threads_mode = "FIXED" if job["threads"] > 0 else "AUTO"
    if job["threads"] > 0:
        s.render.threads = job["threads"]
    s.view_settings.view_transform = "Standard"
    s.view_settings.look = "None"
    s.view_settings.exposure = 0.0
    s.view_settings.gamma = 1.0
    # A black world: no light from outside the scene; with "sky", a world of
    # constant radiance (Background colour x strength 1), which camera rays do
    # not see (vismask's image is black where no surface is).
    w = bpy.data.worlds.new("black")
    w.use_nodes = False
    w.color = (0.0, 0.0, 0.0)
    if job.get("sky"):
        w.use_nodes = True
        nt = w.node_tree
        bg = nt.nodes["Background"]
        if isinstance(job["sky"], dict):
            # A sky map: the world direction turned 90 degrees about X, so
            # that the scene's +Y (up) is the Z up of Cycles' equirectangular
            # mapping and its -Z Blender's +Y (as Blender's OBJ importer
            # turns a Y-up file); texel-constant, as vismask reads the map.
            env = nt.nodes.new("ShaderNodeTexEnvironment")
            env.image = bpy.data.images.load(job["sky"]["file"])  # float: linear
            env.interpolation = "Closest"
            coord = nt.nodes.new("ShaderNodeTexCoord")
            turn = nt.nodes.new("ShaderNodeMapping")
            turn.vector_type = "POINT"
            turn.inputs["Rotation"].default_value = (math.pi / 2, 0.0, 0.0)
            nt.links.new(coord.outputs["Generated"], turn.inputs["Vector"])
            nt.links.new(turn.outputs["Vector"], env.inputs["Vector"])
            nt.links.new(env.outputs["Color"], bg.inputs["Color"])
        else:
            bg.inputs["Color"].default_value = (job["sky"][0], job["sky"][1], job["sky"][2], 1.0)
        bg.inputs["Strength"].default_value = 1.0
        w.cycles_visibility.camera = False
    s.world = w
    if job.get("sun"):
        sun = job["sun"]
        e = max(sun["irradiance"])
        data = bpy.data.lights.new("sun", "SUN")
        data.energy = e  # Cycles: a sun's strength is the irradiance (W/m^2) facing it
        data.color = tuple(c / e if e > 0 else 0.0 for c in sun["irradiance"])
        data.angle = math.radians(sun["degrees"])
        data.cycles.cast_shadow = True
        obj = bpy.data.objects.new("sun", data)
        # A sun lamp shines along its local -z: local +z towards the sun.
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector(sun["toward"]).to_track_quat("Z", "Y")
        s.collection.objects.link(obj)
    s.frame_current = 1
    vl = s.view_layers[0]
    vl.use_pass_combined = True
    vl.use_pass_emit = True
    # The compositor writes the Combined and Emit passes as 32-bit float EXR.
    s.use_nodes = True
    nt = s.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    rl = nt.nodes.new("CompositorNodeRLayers")
    comp = nt.nodes.new("CompositorNodeComposite")
    nt.links.new(rl.outputs["Image"], comp.inputs["Image"])
    fo = nt.nodes.new("CompositorNodeOutputFile")
    fo.base_path = job["work"]
    fo.format.file_format = "OPEN_EXR"
    fo.format.color_depth = "32"
    fo.format.exr_codec = "ZIP"
    fo.file_slots.clear()
    fo.file_slots.new("combined_")
    fo.file_slots.new("emit_")
    nt.links.new(rl.outputs["Image"], fo.inputs[0])
    nt.links.new(rl.outputs["Emit"], fo.inputs[1])
    s.render.use_compositing = True
    s.render.filepath = os.path.join(job["work"], "unused_")


def LoadPixels(path, w, h):
    """RGBA floats, row 0 at the bottom (Blender's order), exactly as stored."""
    if not os.path.exists(path):
        Fail("Cycles did not write " + path)
    img = bpy.data.images.load(path)
    img.colorspace_settings.name = "Non-Color"  # the raw floats, no transform
    if tuple(img.size) != (w, h):
        Fail("%s is %dx%d, expected %dx%d" % (path, img.size[0], img.size[1], w, h))
    px = array.array("f", bytes(4 * 4 * w * h))
    img.pixels.foreach_get(px)
    return px


def WritePfm(path, px, w, h):
    # PFM: "PF", width height, -1 (little-endian), rows bottom to top: Blender's
    # row order already.
    rgb = array.array("f", bytes(4 * 3 * w * h))
    rgb[0::3] = px[0::4]
    rgb[1::3] = px[1::4]
    rgb[2::3] = px[2::4]
    if sys.byteorder != "little":
        rgb.byteswap()
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(rgb.tobytes())


def WriteMask(path, emit, w, h, dilate):
    # 255 where the Emit pass (emission seen directly by camera rays; the back
    # side of an emitter emits nothing) is nonzero in any channel, dilated by
    # `dilate` pixels (a (2d+1)^2 square); PGM rows run top to bottom.
    hit = bytearray(w * h)
    for y in range(h):
        row = (h - 1 - y) * w  # Blender row 0 is the bottom
        for x in range(w):
            k = 4 * (row + x)
            if emit[k] > 0.0 or emit[k + 1] > 0.0 or emit[k + 2] > 0.0:
                hit[y * w + x] = 1
    mask = dilated_mask(hit, w, h, dilate)
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (w, h))
        f.write(bytes(mask))
    return sum(1 for v in mask if v)


def Main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        Fail("usage: blender -b --python blender_render.py -- JOB.json")
    with open(argv[0]) as f:
        job = json.load(f)
    ClearScene()
    Settings(job)
    mats = [MakeMaterial("m%d" % i, m["kd"], m["ke"], m.get("two_sided", False),
                         m.get("camera_only_emission", False))
            for i, m in enumerate(job["materials"])]
    mesh = bpy.data.meshes.new("scene")
    mesh.from_pydata([tuple(v) for v in job["vertices"]], [], [tuple(f) for f in job["faces"]])
    for m in mats:
        mesh.materials.append(m)
    mesh.polygons.foreach_set("material_index", job["face_materials"])
    mesh.polygons.foreach_set("use_smooth", [False] * len(job["faces"]))
    mesh.update()
    if len(mesh.polygons) != len(job["faces"]):
        Fail("Blender kept %d of %d faces" % (len(mesh.polygons), len(job["faces"])))
    obj = bpy.data.objects.new("scene", mesh)
    bpy.context.scene.collection.objects.link(obj)
    vs = job["vertices"]
    lo = [min(v[i] for v in vs) for i in range(3)]
    hi = [max(v[i] for v in vs) for i in range(3)]
    MakeCamera(job["camera"], math.dist(lo, hi))
    for lamp in job.get("area_lamps", []):
        AreaLamp(lamp, math.dist(lo, hi))
    t0 = time.time()
    bpy.ops.render.render(write_still=False)
    seconds = time.time() - t0
    w, h = job["width"], job["height"]
    combined = LoadPixels(os.path.join(job["work"], "combined_0001.exr"), w, h)
    emit = LoadPixels(os.path.join(job["work"], "emit_0001.exr"), w, h)
    WritePfm(job["pfm"], combined, w, h)
    masked = WriteMask(job["pgm"], emit, w, h, job["mask_dilate"])
    with open(os.path.join(job["work"], "stats.json"), "w") as f:
        json.dump({"render_seconds": seconds, "masked_pixels": masked,
                   "blender": bpy.app.version_string}, f)


Main()
