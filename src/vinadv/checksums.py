"""The SHA-256 of a file's bytes: what identifies weights files, the maps a run read and a planner's own files in
vinadv's records. Read in blocks of 1 MiB, so a file of any size takes little memory."""

from __future__ import annotations

import hashlib
import os


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of the file's bytes, as hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
