"""Clips given as URLs (``http://``, ``https://``, ``s3://``, ``file://``, ...): fetched once into a local cache.

The batch engine's workers (:mod:`vistrack.engine.grid`) need no filesystem in common with the client:
a clip may be named by a URL that each worker reads with `fsspec <https://filesystem-spec.readthedocs.io>`_
(``http(s)://`` through aiohttp; ``s3://``, ``gs://`` and others when their fsspec package is
installed). A clip folder's files (video or images, ground truth, meta.json) are copied once into
``$VISTRACK_CACHE`` (default ``~/.cache/vistrack/clips``), under a hash of the URL, and read there.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

__all__ = ["is_url", "local_clip", "CACHE"]

#: where fetched clips are kept
CACHE = Path(os.environ.get("VISTRACK_CACHE", Path.home() / ".cache" / "vistrack")) / "clips"


def is_url(path):
    """Whether ``path`` is a URL (``scheme://...``) rather than a local path."""
    return "://" in str(path)


def local_clip(path, cache=None):
    """A local path for clip ``path``: ``path`` itself when it is local (``file://`` stripped), else
    the clip folder (or file) fetched from the URL into ``cache`` once (a partial fetch is never
    used: it is fetched into a temporary folder and renamed). An unreachable URL is an ``OSError``."""
    s = str(path)
    if not is_url(s):
        return Path(s)
    if s.startswith("file://"):
        return Path(s[len("file://"):])
    import fsspec

    url = s.rstrip("/")
    name = url.rsplit("/", 1)[-1] or "clip"
    root = Path(cache or CACHE) / hashlib.sha256(url.encode()).hexdigest()[:16]
    dest = root / name
    if dest.exists():
        return dest
    fs, rpath = fsspec.core.url_to_fs(url)
    tmp = root / f".{name}.partial-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.parent.mkdir(parents=True, exist_ok=True)
    try:
        if fs.isdir(rpath):
            for f in fs.find(rpath):
                rel = f[len(rpath):].lstrip("/") if f.startswith(rpath) else f.rsplit("/", 1)[-1]
                if not rel or rel.endswith("/"):
                    continue
                target = tmp / rel
                target.parent.mkdir(parents=True, exist_ok=True)
                fs.get_file(f, str(target))
        else:
            fs.get_file(rpath, str(tmp))
        try:
            os.replace(tmp, dest)
        except OSError:
            if not dest.exists():  # else another process fetched it first: theirs is as good
                raise
    except FileNotFoundError as e:
        raise OSError(f"cannot fetch the clip {s}: {e}") from None
    except Exception as e:
        if isinstance(e, OSError):
            raise
        raise OSError(f"cannot fetch the clip {s}: {type(e).__name__}: {e}") from None
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return dest
