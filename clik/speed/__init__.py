"""Joint speed limits, kept by time scaling of the reference around the loop.

``speed_limits`` holds the settings and the per-sample ratio, ``time_scaling``
the next time scaling from a run's joint speeds, ``velocity_limits`` the passes
(``track_within_limits``).
"""
