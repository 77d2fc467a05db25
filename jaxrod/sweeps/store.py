"""A sweep's folder: `sweep.json` (all metadata and a fingerprint) and one atomically written
`chunk_XXXXX.npz` per finished chunk."""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Callable

import numpy as np


__all__ = []


def _fingerprint(meta: dict) -> str:
    keep = {k: meta[k] for k in ("spec", "names", "shape", "combine", "seed", "n", "dt", "dtype", "members")}
    keep["inputs"] = {k: np.asarray(v).tolist() for k, v in meta["_inputs"].items()}
    return hashlib.sha256(json.dumps(keep, sort_keys=True, default=str).encode()).hexdigest()


def _meta_file(path):
    return os.path.join(path, "sweep.json")


def _chunk_file(path, c):
    return os.path.join(path, f"chunk_{c:05d}.npz")


def _read_meta(path):
    f = _meta_file(path)
    if not os.path.exists(f):
        return None
    with open(f) as fh:
        return json.load(fh)


def _atomic_write(path: str, write: Callable[[str], None], suffix: str) -> None:
    d = os.path.dirname(path)
    fd, tmp = tempfile.mkstemp(dir=d, prefix=".tmp_", suffix=suffix)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _dump_json(meta, f):
    with open(f, "w") as fh:
        json.dump(meta, fh, indent=1, default=str)

