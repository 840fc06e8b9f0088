"""Exploration: where the machines are (consistent placements,
:mod:`.symmetry`), which zone a robot explores next (:mod:`.strategies`,
the paper's Algorithm 1 and baselines, over :mod:`.view`), what is reported
to the refbox (:mod:`.report`) and, 2017+, looking again at a station whose
rotation is unsure (:mod:`.lookout`)."""
