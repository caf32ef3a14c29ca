"""Input and output: results of the analyses and their tables (:mod:`.results`), the
per-quantity time histories they hold (:mod:`.history`), writing files that stay valid when a
run is interrupted (:mod:`.files`), and observers and progress of running analyses
(:mod:`.observers`)."""
