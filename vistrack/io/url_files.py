"""Talking to the server of a URL (HTTP(S) through ``urllib``, any other fsspec filesystem): what it says
of a file (:func:`probe`: status, range requests, length, validators), the files of a clip folder and their
validators (:func:`url_version`), one file downloaded (:func:`download`). Errors are :class:`FetchError`,
one line naming the URL and what failed (the connection, an HTTP status, a file that is not there, a
download cut short). :mod:`vistrack.io.remote` keeps the copies and decides how a URL is read."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FetchError", "Probe", "probe", "url_version", "list_files", "download", "is_http", "size_words",
           "TIMEOUT", "AGENT"]


#: seconds to wait for a server to answer
TIMEOUT = 60


#: how vistrack names itself to servers
AGENT = "vistrack"


#: the validators of a file, by the names servers and fsspec filesystems give them
VALIDATORS = {"etag": ("ETag", "etag", "md5Hash"),
              "last_modified": ("Last-Modified", "LastModified", "last_modified", "updated", "mtime", "created"),
              "length": ("size", "Content-Length")}


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


def size_words(n):
    n = int(n)
    return f"{n} bytes" if n < 10_000 else f"{n / 1e3:.0f} kB" if n < 10_000_000 else f"{n / 1e6:.1f} MB"


def is_http(url):
    return str(url).lower().startswith(("http://", "https://"))


def _reason(e):
    """What failed, in words, for an error of ``urllib``, the socket or a filesystem."""
    import socket
    from urllib.error import HTTPError, URLError

    if isinstance(e, HTTPError):
        said = " ".join(str(e.reason).split())  # urllib's own text may span lines
        if "infinite loop" in said:
            return f"the server redirects it in a loop (HTTP {e.code}, the last redirect: {e.headers.get('Location')})"
        return f"the server answered HTTP {e.code} {said}"
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
    except Exception as e:  # noqa: BLE001 - a filesystem that connects at once (ftp, sftp): its errors in one line
        raise FetchError(f"cannot read {url}: {_reason(e)}") from None


def _info_version(info):
    """The validators in an fsspec ``info`` dict."""
    out = {}
    for key, names in VALIDATORS.items():
        v = next((info[n] for n in names if info.get(n) not in (None, "")), None)
        if v is not None:
            out[key] = int(v) if key == "length" else str(v)
    return out


def list_files(url):
    """``{relative name: (file URL, validators)}`` of the file or clip folder at ``url`` (a file: the
    name ``""``), asking the server for each file's validators."""
    if is_http(url):
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
    files = list_files(str(url).rstrip("/") if not is_http(url) else str(url))
    return files[""][1] if list(files) == [""] else {"files": {n: v for n, (_, v) in files.items()}}


def download(url, source, dest, length, bar):
    """Copy one file, ``source`` (an HTTP URL, or a path on ``url``'s fsspec filesystem), to ``dest``,
    advancing the progress bar ``bar``: a :class:`FetchError` naming it where the server or the
    connection fails or the copy falls short of ``length``; an error writing ``dest`` as it is."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    try:
        if is_http(source):
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
                raise FetchError(f"cannot download {source}: {_reason(e)} after {size_words(got)}") from None
            if not chunk:
                break
            f.write(chunk)
            got += len(chunk)
            bar.update(len(chunk))
    if length is not None and got != length:
        raise FetchError(f"cannot download {source}: the connection ended after {got} of its {length} bytes")
