"""Outputs: what a tracking run returns, and what clik writes, atomically.

``result`` holds :class:`~clik.outputs.result.TrackingResult` (the joint
trajectory, the task record, the status, the summary) with the joint-speed part
of its summary (``velocity_report``); ``io`` atomic writes, JSON and the
``--out`` folder rule; ``out_folder`` an output folder written as one
transaction under a lock; ``export`` a run's joint trajectory as CSV and
ROS-style JSON.
"""
