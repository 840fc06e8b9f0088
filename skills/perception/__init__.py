"""Perception skills: machines from fiducial tags (:mod:`.tags`) and the
signal light by HOG detector and neural network (:mod:`.light`)."""
