"""``clik bench``: the performance suite, with pink side by side, in one process.

The suite lives in the repository, beside ``clik/``, not in the package: clik imports
neither it nor pink, mink or MuJoCo, and a clik installed from a wheel runs without
them. ``clik bench`` (:mod:`clik.commands.bench`) finds this folder in the checkout the
running clik was imported from (an editable install), else in the working folder, and
runs :func:`benchmarks.suite.run_bench`; from the checkout's root,
``python -m benchmarks --out DIR [--quick]`` does the same.

What is measured (all through clik's public API, on the machine it runs on):

- **Step cost** [us per sample] (:mod:`benchmarks.step`): whole runs of
  :meth:`clik.Tracker.run`, ``result.wall_time_s / result.steps`` (the loop's own
  cost: kinematics, law, constraints, recording; the trajectory is sampled before
  the clock starts). Every clik line runs in the compiled engine (``clik._engine``,
  the line's own key) and in the Python one (its ``python_`` twin), interleaved
  with the others. Lines (:mod:`benchmarks.step_lines`): the planar 4R arm on the
  case study's line (law (9)); the Panda's pose task on the shipped circle
  (``panda_circle``) with law (10) and with law (9) (per-row gains inside the
  explicit-Euler bound); the same with three sphere obstacles against every link's
  convex collision geometry and joint-range rows monitored, placed so that no
  obstacle row, or one, is active; and pink's step (:mod:`benchmarks.step_pink`:
  ``FrameTask`` + ``PostureTask``, ``ConfigurationLimit``, ``solve_ik`` +
  ``integrate_inplace``) on the same model and reference, and with its collision
  barrier on the same spheres (``pink_panda_pose_obstacles``).
- **Tick cost** [us per tick] (:mod:`benchmarks.tick`): one Python call per 1 ms
  tick on the same Panda circle, timed over the whole per-tick loop:
  :class:`clik.Controller` (``ctl.step(x_d(t_k), (v_d, w_d)(t_k))``, law (10)),
  pink (:mod:`benchmarks.tick_pink`) and mink through MuJoCo on the same URDF
  (:mod:`benchmarks.tick_mink`, :mod:`benchmarks.mujoco_panda`), each given the
  look-ahead target ``x_d(t_k+1)`` as their examples do; without and with the three
  spheres (clik's obstacle rows, pink's ``SelfCollisionBarrier`` on the spheres
  added to its collision model, :mod:`benchmarks.pink_barrier`; mink's
  ``CollisionAvoidanceLimit``). Every line's recorded joints go through one check
  (:mod:`benchmarks.tick_quality`): pose errors, clearance to the spheres (coal),
  joint speed over the URDF limits.
- **Zoo obstacle run** [us per sample] (:mod:`benchmarks.step_zoo`): the zoo test's
  run (:mod:`benchmarks.zoo`: every robot, a 5 cm line toward a 3 cm sphere, law (10),
  joint-range rows) in the compiled engine, robot by robot; the median over robots
  (robots refused before running are skipped and counted).
- **Single-pose solve** (:mod:`benchmarks.solve`): seeded random reachable Panda
  poses (forward kinematics of random configurations inside the limits), from the
  reference configuration, tolerance 1e-4 m and 1e-3 rad, checked independently of
  each solver (``|p_d - p|`` and ``|log3(R_d R^T)|``): :func:`clik.solve` (compiled
  and Python engines) against pink iterated to convergence (capped,
  :mod:`benchmarks.solve_pink`) on the same targets.
- **Case study** (:mod:`benchmarks.case_study`): the eight shipped runs
  (:data:`clik.scenarios.CASE_STUDY`), total wall time of ``execute()``, with and
  without building (robot loading).
- **Memory** (:mod:`benchmarks.memory`): peak RSS growth of a 10^6-sample planar run
  with full recording and with ``record_every`` decimation, each in a fresh
  subprocess.
- **Sweep** (:mod:`benchmarks.sweep_rate`): runs per second of a fixed sweep on a
  local Dask cluster of 1 and of 2 workers.

Fairness: the compared step variants run interleaved, one whole run of each per
round (the order rotates every round) after one warm-up run each, and the solve
benchmark rotates clik's two engines and pink in blocks of 25 targets. Figures are
medians over rounds (or targets) with p10 and p90; ratios (``ratios`` in
``bench.json``) are pink's median, or the Python engine's, over the compiled
engine's median from the same rounds.

The targets each figure is compared with are data, ``targets.toml`` beside this
file (:mod:`benchmarks.targets`). :func:`benchmarks.suite.run_bench` writes
``out/bench.json`` and ``out/bench.md`` (:mod:`benchmarks.report`); pink, mink and
MuJoCo (``pip install clik[bench]``) are optional: without one, its lines are
``null``, the log and ``bench.md`` say why, and its targets are neither met nor missed.
"""
