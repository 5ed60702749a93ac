"""Files the tool writes for a user (exports, CSV, plots, descriptions): whole or not at all.

:func:`write_atomic` writes to a temporary file in the target's folder, flushes it to disk and
renames it over the target (``os.replace`` is atomic on one file system). A failure on the way (a
full disk, a lost permission) removes the temporary file, leaves any earlier target untouched, and
raises :class:`OSError` naming the **target** file, so the message says which file was not written.
"""

from __future__ import annotations

import os
import tempfile

__all__ = ["write_atomic"]


def write_atomic(path: str | os.PathLike[str], data: bytes | str) -> None:
    """Write ``data`` (text is UTF-8) to ``path`` completely, or leave ``path`` as it was."""
    target = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(target))
    payload = data.encode("utf-8") if isinstance(data, str) else data
    try:
        fd, tmp = tempfile.mkstemp(prefix=".paraspace-", suffix=".part", dir=folder)
    except OSError as err:
        raise OSError(err.errno, err.strerror, target) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except OSError as err:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise OSError(err.errno, err.strerror, target) from None
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
