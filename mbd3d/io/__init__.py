"""Input and output, above the joints and below the analyses: what an analysis hands back and
what goes to and from files.

Results by concern: :mod:`.results` (:class:`Results`, the one object every analysis returns),
:mod:`.store` (the sample store an analysis fills while it runs), :mod:`.body_views` and
:mod:`.joint_views` (what the results say of a body, a point, a joint), :mod:`.history` (the
per-quantity histories they are computed from), :mod:`.exports` (columns, CSV, pandas, NPZ,
terminal tables), :mod:`.joint_coordinates`. Files: :mod:`.files` (written so that they stay
valid when a run is interrupted), :mod:`.model_file` (reading YAML model files),
:mod:`.model_writer` (writing them), :mod:`.urdf` (robots). :mod:`.observers`: observers and progress of running analyses.

What belongs here: what crosses the boundary of a run, into it (model files, URDF) or out
of it (results, tables, exports, observers); not the equations or the analyses themselves.
"""
