"""tools/reference's renders: Blender Cycles run on a job (blender_render.py),
the cache under build/reference-cache/ (keyed by the scene's bytes, camera,
size, spp, seed, kVersion and Blender's version), supersampling, the two
halves with their noise estimate, and the published REF.pfm, REF.mask.pgm
and REF.json (see tools/reference --help)."""

import array
import hashlib
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

from . import ROOT
from .files import read_pfm
from .images import dilated_mask
from .scene_dump import Blobs, Camera, CameraArgs, Dump, InputError, LightArgs, Mesh

kVersion = 1  # of the conventions and the Blender script: part of the cache key
kAreaLampsVersion = 1  # of AreaLamps' rule: in the cache key of scenes it applies to
kMaskDilate = 2
kBlenderScript = os.path.join(ROOT, "tools", "vismask_tools", "blender_render.py")


def Paths(out):
    base = out[:-len(".pfm")]
    return {"pfm": out, "pgm": base + ".mask.pgm", "json": base + ".json"}


def BlenderVersion():
    try:
        p = subprocess.run(["blender", "--version"], capture_output=True, text=True, timeout=120)
    except OSError:
        print("tools/reference: blender not found (tools/install-deps --reference installs it)",
              file=sys.stderr)
        sys.exit(2)
    m = re.search(r"Blender (\S+)", p.stdout)
    return m.group(1) if m else "unknown"


def LoadScene(a):
    """The scene as vismask loads it (vismask scene-dump): refused as vismask
    refuses it (lit by --sky and --sun when given: a scene they light need
    not emit; --camera checked as render checks it at --size). Returns the
    dump, its mesh (Mesh) and the camera: --camera's numbers as given, else
    the front side's (vismask render --view front; scene-dump's
    front_camera), which is vismask's own default where it chooses front
    (scene-dump's camera says which it chooses)."""
    args = LightArgs(a.get("sky"), a.get("sun"))
    if a.get("camera") is not None:
        args += CameraArgs(a["camera"], *a["size"])
    else:
        args += ["--width", str(a["size"][0]), "--height", str(a["size"][1])]
    d = Dump(a["scene"], args)
    cam = [float(c) for c in a["camera"]] if a.get("camera") is not None else Camera(d["front_camera"])
    return d, Mesh(d), cam


def Render(a, argvForRecord):
    """Renders (or finds in the cache) and publishes REF.pfm, .mask.pgm, .json."""
    if a["supersample"] == 1:
        cache = Cached(a, argvForRecord)
        Publish(cache, Paths(a["out"]))
    else:
        px, mask, meta = Image(a, argvForRecord)
        meta["command"] = "tools/reference " + " ".join(argvForRecord)
        WriteResult(px, mask, meta, a["size"], Paths(a["out"]))
    return json.load(open(Paths(a["out"])["json"]))


def Image(a, argv):
    """The cached render for `a` as (RGB floats rows bottom to top, mask bytes
    rows top to bottom, its ref.json); with --supersample K, rendered at K
    times the size and box-averaged over K x K pixels (exactly a 1-pixel box
    filter at the smaller size), the mask the OR over the K x K pixels, dilated
    further so that it covers kMaskDilate pixels at the smaller size."""
    K, (w, h) = a["supersample"], a["size"]
    b = dict(a, size=(K * w, K * h), supersample=1)
    rec = [x for x in argv if x != "--halves"]
    if K > 1:
        rec = ReplaceArg(rec, "--size", str(K * w), str(K * h))
        i = rec.index("--supersample")
        rec = rec[:i] + rec[i + 2:]
    rec = ReplaceArg(ReplaceArg(rec, "--spp", str(a["spp"])), "--seed", str(a["seed"]))
    cache = Cached(b, rec)
    meta = json.load(open(os.path.join(cache, "ref.json")))
    px = read_pfm(os.path.join(cache, "ref.pfm"), top_first=False)[2]
    mask = open(os.path.join(cache, "ref.mask.pgm"), "rb").read()[-K * w * K * h:]
    if K == 1:
        return array.array("f", px), mask, meta
    W = K * w
    out = array.array("f", bytes(12 * w * h))
    for y in range(h):
        for x in range(w):
            for c in range(3):
                out[3 * (y * w + x) + c] = sum(px[3 * ((K * y + j) * W + K * x + i) + c]
                                               for j in range(K) for i in range(K)) / (K * K)
    hit = [any(mask[(K * y + j) * W + K * x + i] for j in range(K) for i in range(K))
           for y in range(h) for x in range(w)]
    extra = kMaskDilate - kMaskDilate // K
    small = dilated_mask(hit, w, h, extra)
    meta.update({"width": w, "height": h, "supersample": K, "rendered_size": [W, K * h],
                 "masked_pixels": sum(1 for v in small if v),
                 "mask": meta["mask"] + " at the rendered size; OR over %dx%d, dilated %d px more"
                 % (K, K, extra)})
    return out, bytes(small), meta


def WriteResult(px, mask, meta, size, out):
    w, h = size
    work = tempfile.mkdtemp(prefix="result.", dir=os.path.dirname(os.path.abspath(out["pfm"])))
    try:
        if sys.byteorder != "little":
            px.byteswap()
        with open(os.path.join(work, "ref.pfm"), "wb") as f:
            f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
            f.write(px.tobytes())
        with open(os.path.join(work, "ref.mask.pgm"), "wb") as f:
            f.write(b"P5\n%d %d\n255\n" % (w, h))
            f.write(mask)
        with open(os.path.join(work, "ref.json"), "w") as f:
            json.dump(meta, f, indent=1)
            f.write("\n")
        Publish(work, out)
    finally:
        shutil.rmtree(work)


def Publish(cache, out):
    # Copies under temporary names beside the outputs, then renames.
    tmp = {k: v + ".tmp%d" % os.getpid() for k, v in out.items()}
    try:
        for k, src in (("pfm", "ref.pfm"), ("pgm", "ref.mask.pgm"), ("json", "ref.json")):
            shutil.copyfile(os.path.join(cache, src), tmp[k])
        for k in tmp:
            os.replace(tmp[k], out[k])
    finally:
        for t in tmp.values():
            if os.path.exists(t):
                os.remove(t)


def Rectangle(corners):
    """(corner, edge1, edge2) when the four corners make a rectangle (to
    1e-6 of its size), else None."""
    if len(corners) != 4:
        return None
    p = corners
    e1 = [p[1][i] - p[0][i] for i in range(3)]
    e2 = [p[3][i] - p[0][i] for i in range(3)]
    l1, l2 = math.sqrt(sum(x * x for x in e1)), math.sqrt(sum(x * x for x in e2))
    if not (l1 > 0.0 and l2 > 0.0):
        return None
    far = max(abs(p[2][i] - (p[0][i] + e1[i] + e2[i])) for i in range(3))
    if far > 1e-6 * (l1 + l2) or abs(sum(x * y for x, y in zip(e1, e2))) > 1e-6 * l1 * l2:
        return None
    return list(p[0]), e1, e2


def AreaLamps(vertices, faces, faceMats, mats):
    """The emitters Cycles renders as rectangular Area lamps: every face of a
    one-sided emitting material whose faces are all rectangles. Cycles 3.4
    samples a mesh light's triangles with a bias where a receiver sees them
    nearly edge-on: on the Cornell box's upper walls, within the light's
    size of its plane, its direct light came out 0.8-1.1% low against the
    exact polygon integral (and against Cycles with the light found by
    BSDF rays alone), while an Area lamp's is exact there. Returns the lamps
    [{corner, edge1, edge2, ke}] and the indices of the materials they
    replace as light sources (the faces stay, for camera rays, the Emit
    pass and their Kd)."""
    lamps, done = [], []
    for m, mat in enumerate(mats):
        if max(mat["ke"]) <= 0.0 or mat["two_sided"]:
            continue
        rects = [Rectangle([vertices[i] for i in f]) for f, fm in zip(faces, faceMats) if fm == m]
        if not rects or any(r is None for r in rects):
            continue
        done.append(m)
        lamps += [{"corner": c, "edge1": e1, "edge2": e2, "ke": list(mat["ke"])}
                  for c, e1, e2 in rects]
    return lamps, done


def Cached(a, argvForRecord):
    """The cache directory holding this render (ref.pfm, ref.mask.pgm,
    ref.json), rendered first if it is not there."""
    scene, (w, h) = a["scene"], a["size"]
    d, (vertices, faces, faceMats, mats), cam = LoadScene(a)
    for m in mats:
        if m["texture"] and not a["quiet"]:
            print("tools/reference: warning: material '%s': its texture %s is not rendered "
                  "(Kd alone)" % (m["name"], m["texture"]), file=sys.stderr)
    outDir = os.path.dirname(os.path.abspath(a["out"]))
    if not os.path.isdir(outDir):
        raise InputError("--out: directory '%s' does not exist" % outDir)
    version = BlenderVersion()
    key = hashlib.sha256()
    for b in Blobs(d):
        key.update(hashlib.sha256(b).digest())
    if not scene.lower().endswith(".obj"):
        # A glTF's buffers and images may be files beside it: the scene as
        # loaded stands for them.
        key.update(hashlib.sha256(json.dumps([faces, faceMats, vertices, mats]).encode()).digest())
    what = {"camera": [float(c) for c in cam], "size": [w, h], "spp": a["spp"],
            "seed": a["seed"], "version": kVersion, "blender": version}
    # Area lamps: in the key only when the scene has them, so the cache of
    # scenes without stays.
    lamps = AreaLamps(vertices, faces, faceMats, mats)
    if lamps[0]:
        what["area_lamps"] = kAreaLampsVersion
    # --sky, --sun: in the key only when given, so the cache of unlit keys stays.
    for k in ("sky", "sun"):
        if a.get(k) is not None:
            what[k] = a[k]
    if isinstance(a.get("sky"), dict):  # a sky map: its bytes, wherever it is
        what["sky"] = {"sha256": a["sky"]["sha256"]}
    key.update(json.dumps(what, sort_keys=True).encode())
    key = key.hexdigest()[:24]
    cache = os.path.join(ROOT, "build", "reference-cache", key)
    if not (a["cache"] and os.path.exists(os.path.join(cache, "ref.json"))):
        Blend(a, vertices, faces, faceMats, mats, lamps, cam, key, version, cache, argvForRecord)
    elif not a["quiet"]:
        print("reference: cached (%s)" % cache, file=sys.stderr)
    return cache


def RenderHalves(a, argv):
    """--halves (--parts 2) and --parts N: N cached renders of spp/N (seeds S
    to S+N-1), averaged, with the noise estimate (see the usage text)."""
    w, h = a["size"]
    n = a.get("parts", 2)
    partArgv = list(argv)
    if "--parts" in partArgv:  # each part's record names its own spp and seed
        i = partArgv.index("--parts")
        partArgv = partArgv[:i] + partArgv[i + 2:]
    halves = [Image(dict(a, spp=a["spp"] // n, seed=a["seed"] + k), partArgv) for k in range(n)]
    px = [x[0] for x in halves]
    meta = [x[2] for x in halves]
    mask = bytes(255 if any(ms) else 0 for ms in zip(*(x[1] for x in halves)))
    avg = array.array("f", [sum(v) / n for v in zip(*px)])
    num = den = 0.0
    for i in range(w * h):
        y, x = divmod(i, w)
        if mask[(h - 1 - y) * w + x]:  # PFM rows bottom to top, PGM top to bottom
            continue
        for c in range(3 * i, 3 * i + 3):
            if n == 2:
                d = px[0][c] - px[1][c]
                num += d * d
            else:
                num += sum((p[c] - avg[c]) ** 2 for p in px)
            den += avg[c] * avg[c]
    # The mean's variance is a part's over n, a part's estimated by sum over
    # parts of (p - mean)^2 / (n - 1): sqrt(num / (n (n - 1)) / den). At n = 2
    # sum (p - mean)^2 = d^2 / 2, which gives sqrt(sum d^2 / den) / 2.
    if den > 0:
        noise = math.sqrt(num / den) / 2 if n == 2 else math.sqrt(num / (n * (n - 1)) / den)
    else:
        noise = 0.0
    m = dict(meta[0])
    m.update({"command": "tools/reference " + " ".join(argv), "spp": a["spp"], "seed": a["seed"],
              ("halves" if n == 2 else "parts"): [
                  {"spp": x["spp"], "seed": x["seed"], "cache_key": x["cache_key"],
                   "wall_seconds": x["wall_seconds"], "threads": x["threads"]} for x in meta],
              "wall_seconds": round(sum(x["wall_seconds"] for x in meta), 1),
              "render_seconds": round(sum(x["render_seconds"] for x in meta), 1),
              "masked_pixels": sum(1 for v in mask if v),
              "mask": meta[0]["mask"] + ("; the union of the two halves' masks" if n == 2 else
                                         "; the union of the %d parts' masks" % n),
              "noise_relative_rmse": round(noise, 6),
              "noise_method": ("sqrt(sum (h1-h2)^2 / sum ((h1+h2)/2)^2) / 2" if n == 2 else
                               "sqrt(sum over parts of (p-mean)^2 / (N (N-1)) / sum mean^2)") +
                              " over the RGB values of unmasked pixels: the estimated relative "
                              "RMSE of this average against the noise-free image"})
    del m["cache_key"]
    WriteResult(avg, mask, m, a["size"], Paths(a["out"]))
    return json.load(open(Paths(a["out"])["json"]))


def ReplaceArg(argv, flag, *values):
    if flag in argv:
        i = argv.index(flag)
        return argv[:i + 1] + list(values) + argv[i + 1 + len(values):]
    return argv + [flag] + list(values)


def Blend(a, vertices, faces, faceMats, mats, lamps, cam, key, version, cache, argvForRecord):
    """Renders the job into `cache`; lamps: AreaLamps' (lamps, materials)."""
    (w, h) = a["size"]
    os.makedirs(os.path.dirname(cache), exist_ok=True)
    work = tempfile.mkdtemp(prefix=key + ".", dir=os.path.dirname(cache))
    p = None
    try:
        job = {"vertices": vertices, "faces": faces, "face_materials": faceMats, "materials": mats,
               "camera": {"eye": cam[0:3], "target": cam[3:6], "up": cam[6:9], "fovy": cam[9]},
               "width": w, "height": h, "spp": a["spp"], "seed": a["seed"],
               "threads": a["threads"], "work": work, "pfm": os.path.join(work, "ref.pfm"),
               "pgm": os.path.join(work, "ref.mask.pgm"), "mask_dilate": kMaskDilate,
               "sky": a.get("sky"), "sun": a.get("sun")}
        job["area_lamps"], done = lamps
        job["materials"] = [dict(m, camera_only_emission=i in done) for i, m in enumerate(mats)]
        with open(os.path.join(work, "job.json"), "w") as f:
            json.dump(job, f)
        # Line-buffered, so that the progress line follows Cycles' own.
        cmd = (["stdbuf", "-oL"] if shutil.which("stdbuf") else []) + [
            "blender", "-b", "--factory-startup", "--python-exit-code", "3",
            "--python", kBlenderScript, "--", os.path.join(work, "job.json")]
        t0 = time.time()
        log = open(os.path.join(work, "blender.log"), "w")
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        sample = re.compile(r"Sample (\d+)/(\d+)")
        for line in p.stdout:
            log.write(line)
            m = sample.search(line)
            if m and not a["quiet"]:
                s, n = int(m.group(1)), int(m.group(2))
                el = time.time() - t0
                print("\rreference: sample %d/%d, %.0f s, %.0f s left   " %
                      (s, n, el, el / max(s, 1) * (n - s)), end="", file=sys.stderr, flush=True)
        rc = p.wait()
        p = None
        log.close()
        seconds = time.time() - t0
        if not a["quiet"]:
            print("", file=sys.stderr)
        if rc != 0 or not os.path.exists(job["pfm"]):
            tail = open(os.path.join(work, "blender.log")).read().splitlines()[-15:]
            print("tools/reference: Blender failed (exit %d); its log ends:\n  %s" %
                  (rc, "\n  ".join(tail)), file=sys.stderr)
            sys.exit(1)
        stats = json.load(open(os.path.join(work, "stats.json")))
        meta = {"command": "tools/reference " + " ".join(argvForRecord),
                "scene": a["scene"], "camera": cam, "width": w, "height": h, "spp": a["spp"],
                "seed": a["seed"], "threads": a["threads"] or os.cpu_count(), "blender": version,
                "script_version": kVersion, "cache_key": key,
                "wall_seconds": round(seconds, 1), "render_seconds": round(stats["render_seconds"], 1),
                "mask": "Cycles Emit pass > 0 in any channel, dilated %d px (square)" % kMaskDilate,
                "masked_pixels": stats["masked_pixels"]}
        for k in ("sky", "sun"):
            if a.get(k) is not None:
                meta[k] = a[k]
        with open(os.path.join(work, "ref.json"), "w") as f:
            json.dump(meta, f, indent=1)
            f.write("\n")
        for name in ("job.json", "combined_0001.exr", "emit_0001.exr"):
            if os.path.exists(os.path.join(work, name)):
                os.remove(os.path.join(work, name))
        if os.path.exists(cache):
            shutil.rmtree(cache)
        os.replace(work, cache)
    finally:
        if p is not None:
            p.kill()
        if os.path.exists(work):
            shutil.rmtree(work)
