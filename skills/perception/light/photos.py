"""Real photographs as backdrops for training and testing the light models.

No image data set can be downloaded here, but scikit-image ships a few
sample photographs and textures inside its wheel, each dedicated to the
public domain or CC0 by its author (see the docstrings of
``skimage.data``).  When scikit-image is installed (``pip install
'rll-bt[vision-train]'``) they are read straight from the package's data
folder; without it :func:`available` is False and training uses only
procedural backgrounds.

The photographs are split: ``TRAIN`` ones back training frames, ``HELDOUT``
ones only the benchmark's frames, so a model is scored on photographs it
never saw.  :func:`photo_backdrop` cuts a random crop (zoomed, mirrored,
rotated by quarter turns, colours shuffled at times) of the size asked;
:func:`backdrop` draws a procedural background, a photograph, or a collage
of photograph patches on a procedural background.  Images are BGR uint8.
"""
from __future__ import annotations

import importlib.util
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

from .backgrounds import procedural_background

# files in skimage/data, each CC0 or public domain by its docstring in skimage.data
TRAIN = ("astronaut.png", "camera.png", "brick.png", "grass.png", "gravel.png", "text.png", "coins.png",
         "clock_motion.png", "hubble_deep_field.jpg", "ihc.png", "retina.jpg", "cell.png")
HELDOUT = ("coffee.png", "rocket.jpg", "chelsea.png")
#: photographs other packages ship, held out as well: (package, path in it); Grace Hopper's
#: portrait in matplotlib's sample data is a US Navy photograph, in the public domain
OTHER_HELDOUT = (("matplotlib", "mpl-data/sample_data/grace_hopper.jpg"),)


def _package_dir(name: str) -> Path | None:
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(list(spec.submodule_search_locations)[0])


def _data_dir() -> Path | None:
    d = _package_dir("skimage")
    return d / "data" if d is not None and (d / "data").is_dir() else None


@lru_cache(maxsize=2)
def photos(split: str = "train") -> tuple[np.ndarray, ...]:
    """The photographs of ``split`` ("train" or "heldout") that can be read."""
    if split not in ("train", "heldout"):
        raise ValueError(f"split must be 'train' or 'heldout', not {split!r}")
    d = _data_dir()
    paths = [d / name for name in (TRAIN if split == "train" else HELDOUT)] if d is not None else []
    if split == "heldout":
        for package, rel in OTHER_HELDOUT:
            p = _package_dir(package)
            if p is not None:
                paths.append(p / rel)
    out = []
    for path in paths:
        img = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if img is not None and min(img.shape[:2]) >= 64:
            out.append(img)
    return tuple(out)


def available(split: str = "train") -> bool:
    return bool(photos(split))


def photo_backdrop(rng: np.random.Generator, h: int, w: int, split: str = "train") -> np.ndarray | None:
    """A random ``h`` x ``w`` crop of a photograph of ``split``, or None without photographs."""
    pics = photos(split)
    if not pics:
        return None
    img = pics[int(rng.integers(len(pics)))]
    k = int(rng.integers(4))
    if k:
        img = np.ascontiguousarray(np.rot90(img, k))
    ih, iw = img.shape[:2]
    # the crop covers the output at a zoom of 1 to 3 beyond the smallest cover
    cover = max(h / ih, w / iw)
    zoom = cover * float(np.exp(rng.uniform(0.0, np.log(3.0))))
    ch, cw = min(ih, int(np.ceil(h / zoom))), min(iw, int(np.ceil(w / zoom)))
    y0, x0 = int(rng.integers(0, ih - ch + 1)), int(rng.integers(0, iw - cw + 1))
    crop = cv2.resize(img[y0:y0 + ch, x0:x0 + cw], (w, h), interpolation=cv2.INTER_LINEAR)
    if rng.random() < 0.5:
        crop = crop[:, ::-1]
    if rng.random() < 0.25:                            # another colour world
        crop = crop[:, :, rng.permutation(3)]
    return np.ascontiguousarray(crop)


def backdrop(rng: np.random.Generator, h: int, w: int, split: str = "train", procedural: float = 0.4) -> np.ndarray:
    """Procedural (a ``procedural`` share, 40 % by default), a photograph
    (35 %) or a collage of photograph patches on a procedural background
    (25 %); procedural only without photographs."""
    r = rng.random()
    if r < procedural or not available(split):
        return procedural_background(rng, h, w)
    if r < procedural + (1 - procedural) * 0.35 / 0.6:
        return photo_backdrop(rng, h, w, split)
    img = procedural_background(rng, h, w, clutter=(0, 12))
    for _ in range(int(rng.integers(2, 6))):
        ph, pw = int(rng.integers(h // 6, h // 1.5)), int(rng.integers(w // 8, w // 1.5))
        patch = photo_backdrop(rng, ph, pw, split)
        y, x = int(rng.integers(0, h - ph + 1)), int(rng.integers(0, w - pw + 1))
        img[y:y + ph, x:x + pw] = patch
    return img
