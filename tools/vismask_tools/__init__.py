"""vismask's tools library: what every report script under tools/ uses.

  cli        the scripts' shared arguments (--quick, --out DIR, --help)
  runner     running vismask (with a run cache keyed by the command line), timed commands
  reps       repeated runs: counts checked equal, timings as median (min–max)
  files      JSON, CSV, PFM, PGM and PNG files, run.json
  images     image error (relative RMSE, as `vismask compare`), difference images,
             the emitter mask's dilation (tools/reference and its Blender script)
  stats      medians with their min-max, percentages
  plot       gnuplot
  markdown   Markdown tables and generated sections of docs/*.md
  machine    facts about the machine and the commit, for reports
  cornell    the Cornell box's shadow region (the experiments' leak figures)
  experiments, groundtruth   the steps of make experiments (docs/RESULTS.md);
             results_report writes it, gt_references and gt_report the ground truth's part,
             gt_silhouettes its errors without the 1-px silhouettes; sun_step the sun room
             against Cycles (sunroom its geometry, sun_edge the shadow-edge width); room_step
             make parallel's pillared room against Cycles, over pixel blocks (coarse, run
             with /usr/bin/python3)
  checks     the checks of one output directory (make stability)
  fuzz       the Fuzzing section of docs/STABILITY.md (make fuzz-report)
  bench_runs, bench_parallel, bench_doc   make bench (bench/run): docs/BENCHMARKS.md
  cluster, cluster_doc   make cluster-experiments: docs/CLUSTER.md
  scene_dump  a scene as vismask loads it (vismask scene-dump): mesh, materials, cameras
  reference_render   tools/reference: the cache, Blender runs
  blender_render, scale      run by tools/reference: inside Blender, and its check
  silhouette  tools/silhouette-mask: the pixels within 1 px of a geometric edge
  renderpark  tools/renderpark-run: a scene as MGF for rpkCpp, its RGBE image as PFM

Scripts in tools/ import it as `from vismask_tools import ...` (Python puts
the script's own directory first on sys.path; bench/run, outside tools/,
adds it); it needs only Python 3's
standard library, except scale.py, silhouette.py and renderpark.py (numpy, /usr/bin/python3)."""
import os

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
