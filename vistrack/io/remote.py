"""Videos and clips given as URLs (``http://``, ``https://``, ``s3://``, ``file://``, any fsspec URL).

A video file over HTTP(S) is read by FFmpeg (OpenCV's, the decoder of local files, so a URL gives
the local file's frames and track) straight from the server, seeking with range requests, when the
server takes them (it answers ``206 Partial Content`` to ``Range: bytes=0-0``). Otherwise (no range
requests, such as ``python -m http.server``; a clip folder; any other fsspec URL) it is downloaded,
with a progress bar, into a cache (``$VISTRACK_CACHE/clips``, default ``~/.cache/vistrack/clips``)
kept under the URL and the server's validators of each file (ETag, Last-Modified, length; for
other filesystems what their ``info`` gives: ETag, modification time, size). The validators are
asked for again on every use: an unchanged copy is used as it is (:attr:`Remote.cached`), a changed
file is downloaded again, and a server that gives none is read anew every time. A partial download
is never used (it goes to a temporary name and is renamed), and a copy is checked before each use
against the length and SHA-256 recorded when it was downloaded: one cut short, changed or replaced
(a disk error, another program) is downloaded again, with a note (:attr:`Remote.repaired`). A cache
that cannot be written (read-only, a file where its folder should be, a full disk) is one error line
naming it and ``$VISTRACK_CACHE``, which moves it.

The batch engine's workers (:mod:`vistrack.batch.cluster`) need no filesystem in common with the
client: each fetches a clip given as a URL into its own cache. Errors are :class:`FetchError`, one
line naming the URL and what failed (the connection, an HTTP status, a file that is not there).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from dataclasses import dataclass, field
from pathlib import Path

from .url_files import FetchError, download, is_http, list_files, probe, size_words, url_version

__all__ = ["is_url", "open_url", "open_remote", "fetch", "url_version", "probe", "Remote", "FetchError", "cache_dir",
           "describe_version"]


def cache_dir():
    """Where fetched videos and clips are kept: ``$VISTRACK_CACHE/clips`` (default
    ``~/.cache/vistrack/clips``)."""
    return Path(os.environ.get("VISTRACK_CACHE", Path.home() / ".cache" / "vistrack")) / "clips"


@dataclass
class Remote:
    """How a URL was read (:func:`open_url`, :func:`fetch`).

    Attributes
    ----------
    url : str
    path : Path or None
        The local copy (a file or a clip folder), or ``None`` where FFmpeg reads the server directly.
    version : dict
        The server's validators of the copy (a folder: ``{"files": {name: validators}}``).
    cached : bool
        A copy already in the cache, checked against the server's validators, was used.
    validated : bool
        The server gave validators to check a copy against (else it is read anew on every use).
    live : bool
        Read as a live stream (the server gives no length and takes no range requests).
    repaired : str or None
        Why the cached copy was not used and the file downloaded again (it was cut short or changed
        since its download), or ``None``.
    """

    url: str
    path: Path | None
    version: dict = field(default_factory=dict)
    cached: bool = False
    validated: bool = True
    live: bool = False
    repaired: str | None = None

    def describe(self):
        """One line: how the URL was read (from the server, a fresh download or the cached copy)."""
        if self.live:
            return f"reading {self.url} as a live stream (no length, no range requests; stop it with Ctrl-C)"
        if self.path is None:
            return (f"reading {self.url} from the server (it takes range requests: FFmpeg seeks in it; "
                    "nothing is downloaded)")
        what = describe_version(self.version)
        if self.cached:
            return (f"{self.url}: using the cached copy {self.path}, unchanged on the server ({what}) and as "
                    "downloaded (its length and SHA-256)")
        if self.repaired:
            return f"downloaded {self.url} again into {self.path}: the cached copy {self.repaired}"
        if not self.validated:
            return (f"downloaded {self.url} into {self.path} (the server gives no ETag, Last-Modified or length "
                    "to check a copy against: it is downloaded on every use)")
        return f"downloaded {self.url} into the cache, {self.path} ({what}; checked again on every use)"

    def record(self):
        """A JSON-ready summary for result files: ``url``, ``version``, ``cached``."""
        return {"url": self.url, "version": self.version, "cached": self.cached}


def describe_version(version):
    """The validators ``version`` in words: ``ETag "x", Last-Modified ..., 12 kB`` (a folder: its files)."""
    files = version.get("files")
    if files is not None:
        from email.utils import parsedate_to_datetime

        total = sum(v.get("length", 0) for v in files.values())
        dated = []
        for v in files.values():
            try:
                dated.append((parsedate_to_datetime(v["last_modified"]), v["last_modified"]))
            except (KeyError, TypeError, ValueError):
                pass
        newest = f", the newest Last-Modified {max(dated)[1]}" if dated else ""
        return f"{len(files)} files, {size_words(total)}{newest}"
    parts = [f"ETag {version['etag']}" if "etag" in version else None,
             f"Last-Modified {version['last_modified']}" if "last_modified" in version else None,
             size_words(version["length"]) if "length" in version else None]
    return ", ".join(p for p in parts if p)


def is_url(path):
    """Whether ``path`` is a URL (``scheme://...``) rather than a local path."""
    return "://" in str(path)


def fetch(url, cache=None, progress=False):
    """A local copy of the file or clip folder at ``url`` (:class:`Remote`), from the cache when the
    server's validators are those of the cached copy and the copy is as it was downloaded
    (:func:`_damaged`), else downloaded (``progress``: a progress bar on stderr) into a temporary folder
    and renamed into the cache, the URL's older copies removed. A cache that cannot be written is a
    :class:`FetchError` naming it (:func:`_cache_error`)."""
    s = str(url)
    name = s.rstrip("/").rsplit("/", 1)[-1].split("?", 1)[0] or "clip"
    files = list_files(s if is_http(s) else s.rstrip("/"))
    if not files:
        raise FetchError(f"cannot read {s}: a folder that lists no files")
    single = list(files) == [""]
    version = files[""][1] if single else {"files": {n: v for n, (_, v) in files.items()}}
    validated = all(v for _, v in files.values())
    root = Path(cache or cache_dir())
    home = root / hashlib.sha256(s.encode()).hexdigest()[:16]
    key = hashlib.sha256(json.dumps(version, sort_keys=True).encode()).hexdigest()[:12] if validated else \
        f"unvalidated-{uuid.uuid4().hex[:12]}"
    dest = home / key / name
    repaired = _damaged(home / key, name, files) if validated and (home / key).exists() else None
    if validated and dest.exists() and repaired is None:
        return Remote(s, dest, version, cached=True)
    try:
        if repaired is not None:
            shutil.rmtree(home / key)
        _download_all(s, name, files, version, home, key, progress)
    except FetchError:
        raise
    except OSError as e:
        raise _cache_error(root, e) from None
    return Remote(s, dest, version, cached=False, validated=validated, repaired=repaired)


def _download_all(url, name, files, version, home, key, progress):
    """Download ``files`` (:func:`_files`) into ``home/key/name`` through a temporary folder, with their
    lengths and SHA-256 in ``home/key/version.json``; the URL's older copies removed."""
    tmp = home / f".{key}.partial-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    from tqdm import tqdm

    total = sum(v.get("length", 0) for _, v in files.values()) or None
    try:
        with tqdm(total=total, unit="B", unit_scale=True, desc=f"downloading {name}", disable=not progress,
                  leave=False) as bar:
            for rel, (src, v) in files.items():
                download(url, src, tmp / name / rel if rel else tmp / name, v.get("length"), bar)
        tmp.mkdir(parents=True, exist_ok=True)
        content = {rel: _content(tmp / name / rel if rel else tmp / name) for rel in files}
        (tmp / "version.json").write_text(json.dumps({"url": url, "version": version, "content": content}, indent=1))
        try:
            os.replace(tmp, home / key)
        except OSError:
            if not (home / key / name).exists():  # else another process fetched the same version first
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for old in home.iterdir():  # the URL's older copies (a version the server no longer has)
        if old.name != key and not old.name.startswith("."):
            shutil.rmtree(old, ignore_errors=True)


def _content(path):
    """``{"bytes", "sha256"}`` of a downloaded file."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return {"bytes": os.path.getsize(path), "sha256": h.hexdigest()}


def _damaged(copy, name, files):
    """Why the cached copy in folder ``copy`` is not as it was downloaded (a file missing, not a file,
    cut short or grown, its content changed; a record without the content: an older vistrack's copy),
    or ``None`` when every file's length and SHA-256 are those recorded."""
    try:
        recorded = json.loads((copy / "version.json").read_text()).get("content")
    except (OSError, ValueError, AttributeError):
        recorded = None
    if not isinstance(recorded, dict) or set(recorded) != set(files):
        return "had no record of its content to check it against"
    for rel, want in recorded.items():
        f = copy / name / rel if rel else copy / name
        shown = f"{name}/{rel}" if rel else name
        if not f.is_file():
            return f"lost {shown} (or it is not a file any more)"
        if os.path.getsize(f) != want.get("bytes"):
            return f"held {os.path.getsize(f)} bytes of {shown}, not the {want.get('bytes')} downloaded"
        if _content(f)["sha256"] != want.get("sha256"):
            return f"held {shown} changed since its download (another SHA-256)"
    return None


def _cache_error(root, e):
    """The :class:`FetchError` of a cache that cannot be written: what, where and how to move it."""
    where = e.filename or root
    return FetchError(f"cannot write the download cache {root} ({e.strerror or e}: {where}); free space there, "
                      "or set VISTRACK_CACHE to a writable folder to keep downloads elsewhere")


def open_url(url, cache=None, progress=False):
    """How to read the video file or clip folder at ``url``: a :class:`Remote` whose ``path`` is
    ``None`` where FFmpeg reads the server itself (an HTTP(S) file whose server takes range requests,
    or a live stream: no length), else a local copy (:func:`fetch`)."""
    if is_http(url):
        p = probe(url)
        if not p.listing and (p.ranges or p.live):
            return Remote(url, None, p.version, live=p.live)
    return fetch(url, cache, progress)


def open_remote(remote):
    """The video (:class:`~vistrack.io.video.VideoSource`) of a URL as :func:`open_url` gave it:
    read from the server, or the local copy; a :class:`~vistrack.io.video.VideoError` naming the URL
    where the copy is not a video."""
    from .video import VideoError, VideoSource, open_video

    if remote.path is None:
        return VideoSource(remote.url, remote=remote)
    try:
        src = open_video(remote.path)
    except VideoError as e:
        raise VideoError(f"{remote.url} is not a video (downloaded to {remote.path}: {e})") from None
    src.remote = remote
    return src
