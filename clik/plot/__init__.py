"""Plots of tracking results: the paper's Figs. 3-5 for any run, and a planar stick drawing.

Axes-level functions draw into a Matplotlib ``Axes`` that the caller owns
(``plt.subplots()`` in a notebook, or a bare :class:`~matplotlib.figure.Figure`):

- :func:`tracking_error`: the task error norm ``|e|`` against time (Fig. 3).
- :func:`obstacle_distance`: the minimum link-obstacle distance with the
  threshold ``d_o`` drawn (Fig. 4).
- :func:`joint`: one joint against time, with its limit and the threshold band
  ``d_q`` drawn (Fig. 5): a revolute joint in degrees, a prismatic joint in
  metres (a continuous joint's cos and sin as they are).
- :func:`planar_stick`: the arm drawn every ``every`` seconds, projected on a
  plane, with the obstacles and their thresholds.
- :func:`task_error`: one task of a several-task run, its error norms against time.

Each takes one result or several (overlaid, one colour each) and marks the
constraint events (docs/method.md, "Activation and release") as vertical lines in
the colour of their run: solid for ``activate``, dashed for ``release``,
dotted for ``skipped``.

File-level functions build figures with :class:`matplotlib.figure.Figure`
(no GUI backend, no global pyplot state) and write PNGs:
:func:`case_study_figures` (``clik demo``) and :func:`save_result_plots`
(``clik solve --plots``), and :func:`task_errors` (one panel per task of a
several-task run). Importing this package neither imports pyplot nor
changes Matplotlib's backend.

Artists clik adds besides the data carry a ``gid`` so that code (and tests)
can find them: ``"threshold"``, ``"limit"``, ``"threshold_band"``,
``"event"``, ``"contact"`` (distance 0), and in stick drawings ``"stick"``,
``"path"``, ``"reference"``, ``"obstacle"``.

Modules (imports go down this list, never up):

- ``_common``: shared helpers (runs, colours, units, axis finishing, saving).
- ``series``: the time series (:func:`tracking_error`, :func:`obstacle_distance`,
  :func:`joint`).
- ``stick``: the stick drawing (:func:`planar_stick`).
- ``tasks``: the tasks of a several-task run (:func:`task_error`, :func:`task_errors`).
- ``case_study``: the paper's case-study figures and their constants.
- ``overview``: the figures of ``clik solve --plots``.
"""

from clik.plot.case_study import (
    CASE_STUDY_JOINT,
    CASE_STUDY_LIMIT,
    CASE_STUDY_THRESHOLD,
    case_study_figures,
    case_study_plots,
)
from clik.plot.overview import result_plots, save_result_plots
from clik.plot.series import joint, obstacle_distance, tracking_error
from clik.plot.stick import planar_stick
from clik.plot.tasks import task_error, task_errors

__all__ = [
    "CASE_STUDY_JOINT",
    "CASE_STUDY_LIMIT",
    "CASE_STUDY_THRESHOLD",
    "case_study_figures",
    "case_study_plots",
    "joint",
    "obstacle_distance",
    "planar_stick",
    "result_plots",
    "save_result_plots",
    "task_error",
    "task_errors",
    "tracking_error",
]
