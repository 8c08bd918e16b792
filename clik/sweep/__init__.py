"""Parameter sweeps and reachability maps on Dask, from a laptop to a cluster.

A *sweep* is a base scenario plus the keys to vary (:mod:`clik.sweep.spec`);
it expands into runs with stable ids, which run in batches, a Dask task each
(:mod:`clik.sweep.execute`, :mod:`clik.sweep.session`), on a local cluster or an
existing one (:mod:`clik.sweep.cluster`), each worker loading its robots once
(:mod:`clik.sweep.worker`). One row per run is written as runs finish
(:mod:`clik.sweep.store`; read back by :mod:`clik.sweep.results`); rerunning a
sweep into the same folder computes only the runs missing there.
:mod:`clik.sweep.report` says what a sweep did.

A *reachability map* (:mod:`clik.sweep.reach`) solves single-pose IK
(:func:`clik.solve`) over a grid of target points: success, iterations and
manipulability ``sqrt(det(J J^T))`` per point (:mod:`clik.sweep.reach_data`),
written as a table and as a self-contained HTML view
(:mod:`clik.sweep.reach_output`, :mod:`clik.sweep.reach_view`).
"""

from clik.sweep.cluster import dask_client
from clik.sweep.execute import run_sweep
from clik.sweep.reach import reach_map
from clik.sweep.reach_data import ReachMap, ReachSpec
from clik.sweep.report import SweepReport
from clik.sweep.results import read_results
from clik.sweep.spec import RunSpec, Sweep, Vary, load_sweep, parse_sweep, run_id
from clik.sweep.store import ResultStore, SweepOutputExistsError

__all__ = [
    "ReachMap",
    "ReachSpec",
    "ResultStore",
    "RunSpec",
    "Sweep",
    "SweepOutputExistsError",
    "SweepReport",
    "Vary",
    "dask_client",
    "load_sweep",
    "parse_sweep",
    "reach_map",
    "read_results",
    "run_id",
    "run_sweep",
]
