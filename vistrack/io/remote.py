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
is never used (it goes to a temporary name and is renamed).

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

__all__ = ["is_url", "open_url", "open_remote", "fetch", "url_version", "probe", "Remote", "FetchError", "cache_dir",
           "describe_version"]

#: seconds to wait for a server to answer
TIMEOUT = 60
#: how vistrack names itself to servers
AGENT = "vistrack"
#: the validators of a file, by the names servers and fsspec filesystems give them
VALIDATORS = {"etag": ("ETag", "etag", "md5Hash"),
              "last_modified": ("Last-Modified", "LastModified", "last_modified", "updated", "mtime", "created"),
              "length": ("size", "Content-Length")}


def cache_dir():
    """Where fetched videos and clips are kept: ``$VISTRACK_CACHE/clips`` (default
    ``~/.cache/vistrack/clips``)."""
    return Path(os.environ.get("VISTRACK_CACHE", Path.home() / ".cache" / "vistrack")) / "clips"


class FetchError(OSError):
    """A URL could not be read: one sentence naming it and what failed."""

    def __str__(self):
        return self.args[0] if self.args else ""


@dataclass
class Probe:
    """What the server says of an HTTP(S) URL: ``status``, ``ranges`` (it answered a range request with
    206), ``length`` (bytes, or ``None``), ``content_type`` and the validators (:attr:`version`)."""

    url: str
    status: int
    ranges: bool
    length: int | None
    content_type: str
    etag: str | None
    last_modified: str | None

    @property
    def version(self):
        """The validators as a dict (``etag``, ``last_modified``, ``length``; those the server gave)."""
        v = {"etag": self.etag, "last_modified": self.last_modified, "length": self.length}
        return {k: x for k, x in v.items() if x is not None}

    @property
    def live(self):
        """A stream without an end (no length, no ranges: a camera's MJPEG, a live feed)."""
        return self.length is None and not self.ranges

    @property
    def listing(self):
        """An HTML page (a server's folder listing: a clip folder)."""
        return self.content_type == "text/html"


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
    """

    url: str
    path: Path | None
    version: dict = field(default_factory=dict)
    cached: bool = False
    validated: bool = True
    live: bool = False

    def describe(self):
        """One line: how the URL was read (from the server, a fresh download or the cached copy)."""
        if self.live:
            return f"reading {self.url} as a live stream (no length, no range requests; stop it with Ctrl-C)"
        if self.path is None:
            return (f"reading {self.url} from the server (it takes range requests: FFmpeg seeks in it; "
                    "nothing is downloaded)")
        what = describe_version(self.version)
        if self.cached:
            return f"{self.url}: using the cached copy {self.path}, unchanged on the server ({what})"
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
        return f"{len(files)} files, {_size(total)}{newest}"
    parts = [f"ETag {version['etag']}" if "etag" in version else None,
             f"Last-Modified {version['last_modified']}" if "last_modified" in version else None,
             _size(version["length"]) if "length" in version else None]
    return ", ".join(p for p in parts if p)


def _size(n):
    n = int(n)
    return f"{n} bytes" if n < 10_000 else f"{n / 1e3:.0f} kB" if n < 10_000_000 else f"{n / 1e6:.1f} MB"


def is_url(path):
    """Whether ``path`` is a URL (``scheme://...``) rather than a local path."""
    return "://" in str(path)


def _is_http(url):
    return str(url).lower().startswith(("http://", "https://"))


def _reason(e):
    """What failed, in words, for an error of ``urllib``, the socket or a filesystem."""
    import socket
    from urllib.error import HTTPError, URLError

    if isinstance(e, HTTPError):
        return f"the server answered HTTP {e.code} {e.reason}"
    r = e.reason if isinstance(e, URLError) else e
    if isinstance(r, ConnectionRefusedError):
        return "connection refused (no server listening there)"
    if isinstance(r, socket.gaierror):
        return "unknown host"
    if isinstance(r, (TimeoutError, socket.timeout)):
        return f"no answer within {TIMEOUT} s"
    if isinstance(r, FileNotFoundError):
        return "no such file there"
    if isinstance(r, ConnectionError) or isinstance(e, URLError):
        return f"the connection failed ({r.strerror if isinstance(r, OSError) and r.strerror else r})"
    return f"{type(e).__name__}: {e}"


def probe(url):
    """Ask an HTTP(S) server about ``url`` (a ``GET`` of its first byte; nothing more is read): a
    :class:`Probe`; a :class:`FetchError` naming the URL for a connection that fails or an HTTP error."""
    from urllib.request import Request, urlopen

    req = Request(url, headers={"Range": "bytes=0-0", "User-Agent": AGENT})
    try:
        with urlopen(req, timeout=TIMEOUT) as r:
            h, status = r.headers, r.status
    except Exception as e:  # noqa: BLE001 - urllib's and the socket's errors, said in one line
        raise FetchError(f"cannot read {url}: {_reason(e)}") from None
    length = None
    if status == 206 and "/" in h.get("Content-Range", ""):
        total = h["Content-Range"].rsplit("/", 1)[1]
        length = int(total) if total.isdigit() else None
    elif h.get("Content-Length", "").isdigit() and h.get("Content-Encoding", "identity") == "identity":
        length = int(h["Content-Length"])
    return Probe(url, status, status == 206, length, h.get("Content-Type", "").partition(";")[0].strip(),
                 h.get("ETag"), h.get("Last-Modified"))


def _fs(url):
    """``(filesystem, path)`` of an fsspec URL; a :class:`FetchError` for a scheme fsspec lacks."""
    import fsspec

    try:
        return fsspec.core.url_to_fs(url)
    except (ImportError, ValueError) as e:
        raise FetchError(f"cannot read {url}: {e}") from None


def _info_version(info):
    """The validators in an fsspec ``info`` dict."""
    out = {}
    for key, names in VALIDATORS.items():
        v = next((info[n] for n in names if info.get(n) not in (None, "")), None)
        if v is not None:
            out[key] = int(v) if key == "length" else str(v)
    return out


def _files(url):
    """``{relative name: (file URL, validators)}`` of the file or clip folder at ``url`` (a file: the
    name ``""``), asking the server for each file's validators."""
    if _is_http(url):
        p = probe(url)
        if not p.listing:
            return {"": (url, p.version)}
        fs, root = _fs(url)
        try:
            found = fs.find(root)
        except Exception as e:  # noqa: BLE001 - fsspec's and aiohttp's errors, said in one line
            raise FetchError(f"cannot list the folder {url}: {type(e).__name__}: {e}") from None
        base = root.rstrip("/") + "/"
        names = {f[len(base):] if f.startswith(base) else f.rsplit("/", 1)[-1]: f for f in found}
        return {n: (f, probe(f).version) for n, f in sorted(names.items()) if n and not n.endswith("/")}
    fs, root = _fs(url)
    try:
        if fs.isdir(root):
            found = fs.find(root, detail=True)
            base = root.rstrip("/") + "/"
            return {f[len(base):]: (f, _info_version(i)) for f, i in sorted(found.items()) if f.startswith(base)}
        return {"": (root, _info_version(fs.info(root)))}
    except FileNotFoundError:
        raise FetchError(f"cannot read {url}: no such file or folder there") from None
    except FetchError:
        raise
    except Exception as e:  # noqa: BLE001 - the filesystem's own errors, said in one line
        raise FetchError(f"cannot read {url}: {type(e).__name__}: {e}") from None


def url_version(url):
    """The server's validators of the file or clip folder at ``url`` now (what :func:`fetch` checks
    a cached copy against): a file's ``{etag, last_modified, length}``, a folder's ``{"files":
    {name: validators}}``."""
    files = _files(str(url).rstrip("/") if not _is_http(url) else str(url))
    return files[""][1] if list(files) == [""] else {"files": {n: v for n, (_, v) in files.items()}}


def _download(url, source, dest, length, bar):
    """Copy one file, ``source`` (an HTTP URL, or a path on ``url``'s fsspec filesystem), to ``dest``,
    advancing the progress bar ``bar``: a :class:`FetchError` naming it where the server or the
    connection fails or the copy falls short of ``length``; an error writing ``dest`` as it is."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    try:
        if _is_http(source):
            from urllib.request import Request, urlopen

            src = urlopen(Request(source, headers={"User-Agent": AGENT}), timeout=TIMEOUT)
        else:
            src = _fs(url)[0].open(source, "rb")
    except FetchError:
        raise
    except Exception as e:  # noqa: BLE001 - the server's, the socket's or the filesystem's, in one line
        raise FetchError(f"cannot download {source}: {_reason(e)}") from None
    got = 0
    with src, open(dest, "wb") as f:
        while True:
            try:
                chunk = src.read(1 << 20)
            except Exception as e:  # noqa: BLE001 - a connection cut mid-way
                raise FetchError(f"cannot download {source}: {_reason(e)} after {_size(got)}") from None
            if not chunk:
                break
            f.write(chunk)
            got += len(chunk)
            bar.update(len(chunk))
    if length is not None and got != length:
        raise FetchError(f"cannot download {source}: the connection ended after {got} of its {length} bytes")


def fetch(url, cache=None, progress=False):
    """A local copy of the file or clip folder at ``url`` (:class:`Remote`), from the cache when the
    server's validators are those of the cached copy, else downloaded (``progress``: a progress bar
    on stderr) into a temporary folder and renamed into the cache, the URL's older copies removed."""
    s = str(url)
    name = s.rstrip("/").rsplit("/", 1)[-1].split("?", 1)[0] or "clip"
    files = _files(s if _is_http(s) else s.rstrip("/"))
    if not files:
        raise FetchError(f"cannot read {s}: a folder that lists no files")
    single = list(files) == [""]
    version = files[""][1] if single else {"files": {n: v for n, (_, v) in files.items()}}
    validated = all(v for _, v in files.values())
    home = Path(cache or cache_dir()) / hashlib.sha256(s.encode()).hexdigest()[:16]
    key = hashlib.sha256(json.dumps(version, sort_keys=True).encode()).hexdigest()[:12] if validated else \
        f"unvalidated-{uuid.uuid4().hex[:12]}"
    dest = home / key / name
    if validated and dest.exists():
        return Remote(s, dest, version, cached=True)
    tmp = home / f".{key}.partial-{os.getpid()}-{uuid.uuid4().hex[:6]}"
    from tqdm import tqdm

    total = sum(v.get("length", 0) for _, v in files.values()) or None
    try:
        with tqdm(total=total, unit="B", unit_scale=True, desc=f"downloading {name}", disable=not progress,
                  leave=False) as bar:
            for rel, (src, v) in files.items():
                _download(s, src, tmp / name / rel if rel else tmp / name, v.get("length"), bar)
        tmp.mkdir(parents=True, exist_ok=True)
        (tmp / "version.json").write_text(json.dumps({"url": s, "version": version}, indent=1))
        try:
            os.replace(tmp, home / key)
        except OSError:
            if not dest.exists():  # else another process fetched the same version first: theirs is as good
                raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for old in home.iterdir():  # the URL's older copies (a version the server no longer has)
        if old.name != key and not old.name.startswith("."):
            shutil.rmtree(old, ignore_errors=True)
    return Remote(s, dest, version, cached=False, validated=validated)


def open_url(url, cache=None, progress=False):
    """How to read the video file or clip folder at ``url``: a :class:`Remote` whose ``path`` is
    ``None`` where FFmpeg reads the server itself (an HTTP(S) file whose server takes range requests,
    or a live stream: no length), else a local copy (:func:`fetch`)."""
    if _is_http(url):
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
