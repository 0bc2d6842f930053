// The --help text of `vismask` (options.h, HelpText); `vismask view`'s is
// in viewer.cpp. Kept apart from the parser so that options.cpp holds only
// the rules.
#include "vismask/app/options.h"

namespace vismask {

const char* UsageText() {
  return R"(vismask - fixed-memory progressive-refinement radiosity

usage:
  vismask render SCENE [options]         solve the scene's diffuse light and
                                         render it into --out DIR (out/)
  vismask footprint SCENE [options]      the memory a render would reserve
  vismask compare A.pfm B.pfm            relative RMSE of A against B
  vismask view OUT_DIR                   look around a render --export mesh
  vismask --help all                     every option, outputs, exit status

scenes read: Wavefront OBJ with its MTL files (Kd reflectance, Ke emitted
exitance, map_Kd textures: PNG, JPEG, BMP, TGA), and glTF 2.0 (.gltf, .glb:
triangles, base colour and its texture, emission, double-sided materials,
the first camera). The light is the faces that emit, those of the
materials --emit NAME=R,G,B names, and the sky and sun outside (--sky,
--sun), which need no emitter in the scene.

examples:
  vismask render scenes/cornell.obj --out out
      the Cornell box, default view, into out/image.png (and .pfm, csv)
  vismask render scenes/real/CornellBox-Glossy.obj --emit light=17,12,4
      a published scene whose light's material its MTL lacks
  vismask render scenes/gltf-cornell/cornell_box.gltf --width 256 --height 256
      a Blender glTF export, its emissive light and double-sided walls
  vismask render scenes/skylight.obj --sky 0.3,0.4,0.6 --sun 1,4,0.5,30,28,25
      a room with no lamp, lit by the sky and the sun through its skylight
  vismask render scenes/cornell.obj --export out/box.glb && vismask view out
      the solved mesh as glTF, to walk through in a browser
)";
}

const char* HelpText() {
  return R"(vismask - fixed-memory progressive-refinement radiosity

usage:
  vismask render SCENE [options]         solve and render a scene (SCENE.obj,
                                         SCENE.gltf or SCENE.glb)
  vismask footprint SCENE [options]      the memory each environment and rank
                                         would reserve, without solving
                                         (render's options; --json for JSON)
  vismask compare A.pfm B.pfm [--exclude MASK.pgm]
                                         relative RMSE and max abs error of A
                                         against B (pixels where MASK.pgm is
                                         nonzero left out)
  vismask verify OUT_DIR                 whether OUT_DIR holds one run's
                                         complete outputs, as its run.json
                                         lists them (exit 0; 1 if not)
  vismask view OUT_DIR [--glb NAME.glb] [--port P]
                                         serve the solved mesh (render
                                         --export) in the viewer page on
                                         localhost and print its URL
                                         ('vismask view --help')
  vismask --help                         this text

render options:
  --out DIR            output directory (default out/); created if missing
  --export FILE.glb    also write the solved mesh as binary glTF 2.0 to
                       FILE.glb (a path from the current directory, not
                       under --out; its directory must exist): every
                       patch's lattice vertices and triangles, COLOR_0 the
                       linear display radiance image.pfm shows there
                       (emission included, unclamped), an unlit material;
                       scene units and the OBJ's axes
  --patch-size L       longest patch edge, scene units (default: largest
                       scene extent / 28)
  --ray-alloc power|fixed
                       how many Monte Carlo rays a shot traces. power (the
                       default): in proportion to the shot's unshot power,
                       --emitted-rays for the whole emitted power, at least
                       --min-rays; a shot worth more than --max-rays shoots
                       that share of its power and keeps the rest for later
                       shots. fixed: --rays every shot (the old default)
  --rays N             fixed: Monte Carlo rays per shot (4096); given alone it
                       selects --ray-alloc fixed
  --emitted-rays M     power: the rays the emitted power is worth (4000000);
                       a shot of power P traces M * P / emitted power rays,
                       rounded up or down at random from the shot's stream
  --min-rays F         power: the fewest rays a shot traces (default 16)
  --max-rays C         power: the most rays a shot traces (default 8192);
                       also Method R's packet bits
  --sampler S          sobol (default): scrambled Sobol' points over a
                       shot's origin x direction; random: independent draws
  --ray-budget N       stop once N form-factor rays have been traced
  --elements K         receivers finer than shooters: each patch is a
                       quadtree of elements that split where the radiosity
                       received changes fast (shadow edges, contact shadows,
                       corners); the pool holds K elements per patch beyond
                       the patches themselves (default 8; 0: no refinement).
                       When it is used up refinement stops (run.json says so)
  --element-depth D    the deepest an element splits, 0-16 (default 4: 1/16
                       of the patch's edge)
  --element-spread S   an element splits only where its quarters' radiosity
                       differs by more than S (relative RMS, default 0.1) and
                       more than its Monte Carlo noise explains
  --element-chi2 X     ... explains: chi-square (3 dof) of its quarters
                       against an even spread above X (default 20)
  --seed S             random seed, unsigned 64-bit (default 1)
  --stop-unshot F      stop when unshot power < F * emitted power, 0 <= F < 1
                       (default 1e-3); 0 needs another stop as well
  --max-shots N        stop after N shots (default: no limit)
  --max-seconds T      stop after T seconds of solving (default: no limit;
                       a time limit makes the result depend on speed).
                       Without --emitted-rays (one rank, power allocation)
                       it plans them: the rays a solve that ends within
                       about T can afford, from the rays per second timed
                       through the scene's grid at init (run.json:
                       emitted_rays, emitted_rays_planned)
  --width W, --height H   image size in pixels (default 512 x 512)
  --camera ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy_deg
                       eye, target, up and vertical field of view (default:
                       the --view side that shows the most front-facing
                       surface, front on a tie)
  --view SIDE          front | back | left | right | top | bottom: frame the
                       scene's bounding box from that side, its larger extent
                       filling the view: front from -z looking +z, back from
                       +z, left from +x and right from -x (as they appear in
                       the front view), top from +y, bottom from -y. Without
                       --view or --camera, the side is chosen by rays from
                       each side's eye: the most image showing the front of
                       a polygon, occlusion included. Not with --camera
  --exposure E         linear exposure for image.png (default: automatic)
  --aa on|off          on: each pixel is the exact area-weighted mean of what
                       it sees (a 1-pixel box filter: every piece's coverage
                       of the pixel square, computed analytically); off: the
                       pixel centre only, quads as two Gouraud triangles
                       (the images before --aa existed); default on
  --direct-samples N   direct light gathered per pixel, 0..1024: the image's
                       direct part is the exact unoccluded irradiance of the
                       emitters times the share of N shadow rays that reach
                       them (rays to the emitters' corners and 4 first; all
                       N only where those disagree); the solve supplies the
                       rest; 0: the solved radiosity alone (the images
                       before it). Default 32 with one environment, 0 with
                       several (where it is refused)
  --smooth on|off      on: where polygons with a smoothing group ('s N') or
                       vertex normals ('vn') meet, the image shades across
                       them smoothly, within the crease angle; default on
  --crease DEG         smoothing's crease angle, 0..180: the most two vertex
                       normals, or two faces of one smoothing group, may
                       differ by and be shaded as one surface (default 30)
  --quiet              no progress line on stderr
  --strict             refuse degenerate, non-planar and self-intersecting
                       faces (exit 2, file:line) instead of mending them:
                       by default a non-planar face is triangulated, a
                       repeated or collinear corner removed, and a face with
                       no area or crossing edges dropped, each kind counted
                       in one warning line; and refuse faces before any
                       usemtl, undefined materials, a missing MTL file and
                       a texture not found as written (by default grey
                       Kd 0.5, or the texture found in another letter case
                       or dropped, each with one warning line)
  --emit NAME=R,G,B    make material NAME an emitter of exitance Ke =
                       (R, G, B), each >= 0, replacing the MTL's Ke (said
                       in a warning when that was not 0); NAME=ka takes the
                       material's Ka (scenes that give the light's strength
                       there); repeatable; a NAME no MTL defines exits 2
  --sky R,G,B          light from a uniform sky of radiance (R, G, B), each
                       >= 0 (W/m^2/sr of scene units), in every direction
                       the scene does not block, as a path tracer's constant
                       world colour; the scene then need not emit
  --sky FILE.hdr       light from a sky map: an equirectangular Radiance HDR
                       image of the radiance in each direction, oriented as
                       Blender's default equirectangular world on a Y-up
                       scene (the centre looks along +X, the top is +Y,
                       three quarters across looks along +Z); a path tracer's
                       world environment texture. A path ending in .hdr or
                       .pic, or holding a '/', is a file
  --sun X,Y,Z,R,G,B[,DEG]
                       light from a sun in direction (X, Y, Z) (towards
                       it), of irradiance (R, G, B) on a surface facing it,
                       DEG degrees across (0 to 90; 0.53). Sky and sun shoot
                       into the scene from its box's faces: the box and the
                       patch size stay the scene's
  --two-sided          both sides of every polygon receive, reflect and show
                       (for scenes wound inconsistently): each polygon is
                       meshed twice, the copy reversed; patches double.
                       An emitter's copy reflects but does not emit unless
                       --two-sided-emitters is given too
  --two-sided-emitters emitters emit from both sides, Ke from each: twice
                       the emitted power of the one-sided emitter (their
                       back sides also reflect)
  --reference REF.pfm  measure the image's relative RMSE against REF.pfm
                       (same size) when the solve ends, in convergence.csv
                       and run.json; the time it takes is not solve time
  --error-every K      with --reference: also every K shots during the solve
  --exclude MASK.pgm   with --reference: leave out of the relative RMSE the
                       pixels where MASK.pgm (8-bit PGM, same size) is
                       nonzero, e.g. visible emitters (tools/reference)
  --correct-unshot on|off
                       on: patches.csv's b includes kd * the ambient term
                       (Cohen's estimate of what the still-unshot power will
                       add, which the image always shows); default off
  --stop-error E       also stop when the estimated relative bias of b from
                       the power not yet shot is below E, 0 < E < 1: the
                       share rho*U/(1-rho) of the radiosity power still to
                       come (times 1-rho with --correct-unshot on), which
                       unlike --stop-unshot counts the 1/(1-rho)
                       amplification of stiff scenes (default: off)

local environments and visibility masks:
  --envs NX[xNY[xNZ]]  split the scene's box into a grid of environments
                       (default 1); each owns only its own patches and grid
  --envs auto[:N]      N environments (default: --ranks, or under mpirun the
                       world size), the grid's shape and its split planes
                       chosen from the scene: each axis cut where the
                       patches (estimated from the polygons' areas) divide
                       evenly, so every slab holds about as many; still a
                       grid. The default when --envs is not given and the
                       run has more than one rank
  --mask-method M      R | B | C | A | none (default R): what a shooter
                       sends on to its neighbours. R: one bit per ray of
                       the shot (--rays or --max-rays bits), each ray routed
                       to the neighbour it leaves for and absorbed in exactly
                       one environment; a neighbour no ray reaches never
                       hears of the shot. B: a hemisphere mask with one ray
                       from the shooter's centre per open pixel (exact at its
                       resolution; the paper's Method B); C: pixels the rays
                       only hit close, only passed stay open, B's ray for the
                       rest; A: from the form-factor rays that hit (cheap,
                       leaks light where no ray hit); none: no mask (light
                       passes occluders)
  --mask-res R         hemisphere mask resolution (A, B, C): R rows (theta) x
                       4R columns (phi), 1 <= R <= 4096 (default 50); given
                       without --mask-method it selects B
  --round-shots K      at most K shots per environment per round (default
                       with several environments or with --round-work: 256,
                       fewer when 6 packets a shot would fill more than
                       512 KiB; otherwise 1).
                       Given alone (no --round-work), the rounds of before:
                       K shots, no work limit
  --round-work N       a round ends for an environment once its shots have
                       done N units of work: grid steps (cells entered plus
                       patches tested), plus, with Method R, 10 a ray, 9 a
                       hit and 41 a shot (with A, B, C and none: 32, 40 and
                       12288); a count that tracks CPU time but never
                       depends on it, so rounds are the same whatever the
                       machine, ranks or transport. Default with several
                       environments: about 32 full shots' worth (32 x
                       (--max-rays, or --rays, x (the cube root of an
                       environment's grid cells + a ray's and a hit's work)
                       + a shot's)); 0: no limit
  --centre-rays W      all | read | auto (default auto): which open pixels
                       Method B casts a centre ray through. all: every one
                       that leads to a neighbour, each packet's priority and
                       power in flight from its whole mask; read: only those
                       the shot's rays will read downstream (each
                       environment's rays are known from the shot's key), the
                       priority and power in flight from the receiver's rays
                       that pass; auto: read for a shot whose rays x
                       (environments - 1) are at most a quarter of the 4R^2
                       pixels, else all. The same light lands at the
                       pixels read; the shots' order may differ
  --mask-cache K       KiB per environment for Methods B and C's centre masks
                       of local shooters, kept for their later shots (the
                       mask depends only on the shooter); same output,
                       fewer centre rays; 0: none (default 8192)
  --queue Q            foreign shooters an environment holds at once; a
                       full queue holds back new ones (default: the
                       environments x the round's shots, so that every
                       environment can make a whole round, but at most 64
                       an environment and 1 MiB of slots; at least 64)
  --ranks N            run on N processes on this host, connected by POSIX
                       pipes (default 1); environments are dealt to ranks in
                       contiguous blocks; N <= the number of environments
  --transport T        loop | pipe | mpi: loop keeps every environment in
                       one process; pipe is the default for --ranks > 1; mpi
                       is what build/vismask-mpi uses (under mpirun)
  --rank-timeout S     a rank that waits for a peer and hears nothing from
                       it for S seconds ends the run (exit 3, naming the
                       silent rank; a stopped or hung rank). The limit is
                       S or 10 times the longest wait of the run so far,
                       whichever is longer, so S must exceed how much
                       longer one rank's round or init takes than another's
                       and rank 0's output writing (default 60; 0: wait
                       forever)
  --checkpoint DIR     write the solve's state to DIR at a round's end every
                       --checkpoint-every seconds of solve, and when the run
                       gets SIGINT, SIGTERM or SIGHUP (it then ends with
                       128 + the signal, no outputs): one file per
                       environment on the rank holding it, written
                       atomically, and DIR/manifest on rank 0 naming the
                       newest complete checkpoint (a second signal ends the
                       run at once)
  --checkpoint-every S seconds of solve between checkpoints (default 300;
                       0: every round)
  --resume DIR         go on from DIR's newest complete checkpoint (and keep
                       checkpointing there): the outputs are the bytes a run
                       never stopped gives. Give the same scene and options;
                       --ranks, --transport, --out, --export, --quiet,
                       --rank-timeout, --mem-budget, --checkpoint and
                       --checkpoint-every may differ (without --envs, the
                       checkpoint's environments); another scene or option
                       is refused
                       (exit 2, naming the difference). Each rank needs the
                       files of the environments it now holds in DIR
  --mem-budget BYTES   refuse at init (exit 2, with the numbers) when a rank
                       would reserve more than BYTES (suffix K, M or G for
                       KiB, MiB, GiB); a run that starts never runs out
  --env-order I,J,...  run the environments in this order within each round
                       (a permutation of 0..N-1); a check of determinism:
                       the results must not change

outputs (in --out DIR):
  image.png         tone-mapped sRGB image
  image.pfm         linear float RGB radiance (B/pi, with the ambient term)
  patches.csv       id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b
                    (b = solved radiosity, without the ambient term)
  convergence.csv   shot,seconds,unshot_fraction (one row per round: each
                    environment's shots of that round); with --reference two
                    more columns, relative_rmse,error_seconds (filled on the
                    rows where the error was measured; error_seconds is the
                    total spent measuring so far, not part of seconds)
  run.json          options, counts, energy balance, timings, memory
  FILE.glb          with --export (where it names): the solved mesh, glTF 2.0

view (vismask view OUT_DIR):
  serves, on 127.0.0.1 with python3's http.server, the viewer page and
  OUT_DIR, and prints the URL: the mesh 'render --export OUT_DIR/NAME.glb'
  wrote, shown as image.png shows it (exposure slider, sRGB), to orbit
  (drag) or fly through (F; W A S D), starting from run.json's camera.
  --glb NAME.glb       the mesh in OUT_DIR (default: the one .glb there)
  --port P             the port (default: any free port)
  The page is found beside the binary: PREFIX/share/vismask/viewer when
  installed (make install), viewer/ in the source tree (make viewer).

exit status: 0 success; 1 an output could not be written (view: the viewer
page or python3 is missing); 2 bad input or
options (the message names file:line or the option); 3 a rank was lost
or silent (--rank-timeout); 4 the solve stalled (no environment could shoot
while power was left); with --checkpoint, 128 + the signal (130 for SIGINT)
after a signal, its checkpoint written
)";
}

}  // namespace vismask
