"""The one way vinadv reads a JSON document of its own (a model zoo index, a benchmark index, a benchmark entry):
an object whose field 'format' names what it is, refused with one line naming the file otherwise."""

from __future__ import annotations

import json
import os
from pathlib import Path

from vinadv.errors import InputError


def read_json_document(path: str | os.PathLike, document_format: str, what: str) -> dict:
    """The JSON object in the file `path` whose field 'format' is `document_format`; InputError naming the file and
    `what` it should be (e.g. "model zoo index") for a file that cannot be read, is not JSON, or is another
    document (or is not a regular file: a FIFO, a device)."""
    if Path(path).exists() and not Path(path).is_file():  # a FIFO or a device would block the read, or never end
        raise InputError(f"{path}: not a regular file: not a readable {what}")
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except RecursionError:
        raise InputError(f"{path}: not a readable {what} (nested too deep)") from None
    except (OSError, ValueError) as exc:  # ValueError: not UTF-8, not JSON, an integer of too many digits
        raise InputError(f"{path}: not a readable {what} ({str(exc).splitlines()[0]})") from None
    if not isinstance(data, dict) or data.get("format") != document_format:
        raise InputError(f"{path}: field 'format' is not {document_format!r}: not a {what}")
    return data
