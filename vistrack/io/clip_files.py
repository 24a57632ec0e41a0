"""The names of a clip's files, in one place: the suffixes of images, videos and text, the folders of
frames, the ground-truth files and vistrack's own records, what a run reads, and the ground truth's
pixel convention.

**Whether a ground-truth file counts pixels from 1** is decided by the file's name and its dataset's
convention, never by the layout of the frames beside it (an ``img/`` folder or a video): the same
sequence as ``img/`` + ``groundtruth_rect.txt`` and as ``seq.mp4`` + ``groundtruth_rect.txt`` gives the
same boxes (:func:`groundtruth_origin`):

- a clip vistrack wrote (one of :data:`SYNTH_RECORDS` beside it: ``synth perturb``, ``synth plate-on-car``):
  0-based, whatever its ground truth's name;
- ``groundtruth_rect.txt``: OTB's file, 1-based (OTB's toolkit, and DTB70's and UAV123's, which read theirs
  as OTB's);
- ``groundtruth.txt`` beside LaSOT's ``full_occlusion.txt`` or ``out_of_view.txt``: LaSOT's, 1-based;
- ``groundtruth.txt`` otherwise: VOT's and GOT-10k's, 0-based; ``groundtruth.csv``: vistrack's, 0-based;
- any other file (``--init-gt FILE``): 0-based.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["IMAGE_EXT", "VIDEO_EXT", "TEXT_EXT", "FRAME_FOLDERS", "GROUNDTRUTH_FILES", "ONE_BASED", "LASOT_FLAGS",
           "SYNTH_RECORDS", "CLIP_FILES", "groundtruth_origin", "find_groundtruth"]

#: the image files an image folder's frames are read from
IMAGE_EXT = {".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".ppm", ".pgm", ".webp"}
#: the video files a clip folder's video is found by
VIDEO_EXT = {".mp4", ".avi", ".mov", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg", ".wmv"}
#: files FFmpeg's text/data demuxers would "decode", which are never videos here
TEXT_EXT = {".txt", ".csv", ".json", ".md", ".rst", ".xml", ".yaml", ".yml", ".log", ".py", ".html", ".srt"}
#: the folders of a clip that hold its frames: OTB's and LaSOT's ``img/``, VOT's ``color/``
FRAME_FOLDERS = ("img", "color")
#: box ground truth as text, by name, in the order it is looked for: OTB's, then VOT's, GOT-10k's and LaSOT's
GROUNDTRUTH_FILES = ("groundtruth_rect.txt", "groundtruth.txt")
#: the ground-truth files whose datasets count pixels from 1 (OTB; LaSOT's ``groundtruth.txt`` by its flags)
ONE_BASED = ("groundtruth_rect.txt",)
#: LaSOT's flag files: a ``groundtruth.txt`` beside one of them is LaSOT's (1-based)
LASOT_FLAGS = ("full_occlusion.txt", "out_of_view.txt")
#: the record each ``vistrack synth`` command writes beside its clip, and the keys that name what it is
#: (a clip vistrack wrote: its box ground truth is 0-based whatever its name)
SYNTH_RECORDS = {"meta.json": ("kind", "model"), "perturb.json": ("source",), "composite.json": ("source",)}
#: the files of a clip folder that a run reads besides the frames (an output must not be one of them:
#: :func:`vistrack.io.outputs.check_not_input`)
CLIP_FILES = ("video.mp4", "groundtruth.csv", *GROUNDTRUTH_FILES, "meta.json", "objects.csv")


def groundtruth_origin(gt_path):
    """The pixel origin of the box ground-truth file ``gt_path``, 1 or 0, by its name and its dataset's
    convention (module docstring), not by whether an ``img/`` folder is beside it."""
    p = Path(gt_path)
    if any((p.parent / record).is_file() for record in SYNTH_RECORDS):
        return 0
    if p.name in ONE_BASED:
        return 1
    if p.name == "groundtruth.txt" and any((p.parent / flag).is_file() for flag in LASOT_FLAGS):
        return 1
    return 0


def find_groundtruth(path):
    """The box ground truth beside a video or in a clip folder (:data:`GROUNDTRUTH_FILES`), or ``None``."""
    p = Path(path)
    folder = p if p.is_dir() else p.parent
    for name in GROUNDTRUTH_FILES:
        if (folder / name).is_file():
            return folder / name
    return None

