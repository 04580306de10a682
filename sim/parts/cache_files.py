"""Files of the derived-part cache written whole or not at all.

Several processes may derive one part at once: the two workers of ``make test``, the workers of a sweep,
two users of one cache. Each writes under a temporary name of its own and moves the file into place in
one step, so a reader finds the old file, the new one, or none, never half of one.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path


def write_whole(path: Path, data: bytes | str) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` in one step, making its folder if need be."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        tmp.write_bytes(data.encode() if isinstance(data, str) else data)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
