"""Where the ``.proto`` sources of each message set live, and their hashes.

A message set is one directory ``proto/<name>/`` of ``.proto`` files compiled
together into one descriptor pool.  The hashes are computed over the text
with line endings normalised to ``\\n``, so a checkout with CRLF endings hashes
the same as one with LF.
"""
from __future__ import annotations

import hashlib
from pathlib import Path

#: Every message set, in the order they are generated.
SETS: tuple[str, ...] = ("rcll2016", "rcll2025", "team")

#: The package directory: holds ``proto/`` and the generated ``_gen_<set>.py``.
PACKAGE_DIR = Path(__file__).resolve().parent


def proto_dir(set_name: str, package_dir: Path = PACKAGE_DIR) -> Path:
    """Directory holding the ``.proto`` files of ``set_name``."""
    return Path(package_dir) / "proto" / set_name


def generated_module_path(set_name: str, package_dir: Path = PACKAGE_DIR) -> Path:
    """Path of the generated Python module of ``set_name``."""
    return Path(package_dir) / f"_gen_{set_name}.py"


def proto_files(set_name: str, package_dir: Path = PACKAGE_DIR) -> list[Path]:
    """The ``.proto`` files of a set, sorted by name."""
    return sorted(proto_dir(set_name, package_dir).glob("*.proto"))


def file_sha256(path: Path) -> str:
    """SHA-256 (hex) of a source file's text with ``\\n`` line endings."""
    data = Path(path).read_bytes().replace(b"\r\n", b"\n")
    return hashlib.sha256(data).hexdigest()


def source_hashes(set_name: str, package_dir: Path = PACKAGE_DIR) -> dict[str, str]:
    """``{file name: sha256}`` for every ``.proto`` of the set."""
    return {p.name: file_sha256(p) for p in proto_files(set_name, package_dir)}


def combined_sha256(hashes: dict[str, str]) -> str:
    """One SHA-256 over the per-file hashes (names included, sorted)."""
    h = hashlib.sha256()
    for name in sorted(hashes):
        h.update(f"{name}\0{hashes[name]}\n".encode())
    return h.hexdigest()
