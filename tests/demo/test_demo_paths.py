"""`vistrack demo` finds the real clip whichever the working folder (issue 37, item 4)."""

from vistrack.demo.steps import REAL_CLIP, find_real_clip


def test_the_real_clip_is_found_from_a_folder_below_the_one_holding_shared(tmp_path, monkeypatch):
    clip = tmp_path / REAL_CLIP
    clip.mkdir(parents=True)
    deep = tmp_path / "clone" / "sub" / "dir"
    deep.mkdir(parents=True)
    monkeypatch.delenv("VISTRACK_REAL_DATA", raising=False)
    monkeypatch.chdir(deep)
    assert find_real_clip() == clip.resolve()


def test_vistrack_real_data_names_the_folder(tmp_path, monkeypatch):
    (tmp_path / "data" / "girl_otb").mkdir(parents=True)
    monkeypatch.setenv("VISTRACK_REAL_DATA", str(tmp_path / "data"))
    monkeypatch.chdir(tmp_path)
    assert find_real_clip() == tmp_path / "data" / "girl_otb"
