"""The shipped light models, written by ``rll-bt vision train-light --out skills/perception/light/models``:
``tower_hog_svm.npz`` (detector vector and settings), ``light_mlp.npz`` (network weights) and
``training_report.json`` (options and held-out results of the run that made them)."""
