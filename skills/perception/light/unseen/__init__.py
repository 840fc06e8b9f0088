"""Signal towers drawn by renderers the shipped models never learn from.

- :mod:`.raycast`: renderer B, stacked cylinders ray-cast with their own
  materials, light and camera;
- :mod:`.sketch`: renderer C, flat vector drawings, deliberately unlike
  every other renderer here;
- :mod:`.compose`: frames of either on real photographs (those training
  never sees, by default), through that renderer's camera (exposure,
  blur, noise, JPEG).

``benchmarks/light_detection.py`` tests the models on them; the reverse
experiment (train on renderer B, test on the project's renderer) uses
training photographs.  Nothing under :mod:`skills.perception.light`'s
training imports this package (``tests/perception/test_unseen_renderers.py``
checks that).
"""
