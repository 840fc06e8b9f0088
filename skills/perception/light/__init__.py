"""The signal light: the paper's HOG detector + network chain.

- :mod:`.hog`: the tower detector (HOG, linear SVM by OpenCV's recipe, pyramid and region search)
- :mod:`.mlp`, :mod:`.scg`: the network over tower crops, trained with Moller's scaled conjugate gradient
- :mod:`.reader`: :class:`~.reader.LightReader`, detector -> crop -> network, with the shipped models
- :mod:`.region`: where a station's tag says its tower is in the image
- :mod:`.temporal`: per-frame states to ON / OFF / BLINK per light
- :mod:`.colour_model`: the colour-threshold baseline (Carologistics style)
- :mod:`.scenes`, :mod:`.dataset`, :mod:`.augment`, :mod:`.backgrounds`, :mod:`.synth`,
  :mod:`.training`, :mod:`.evaluation`: ``rll-bt vision train-light``
"""
