"""The start box, documented and helpful (issue 46, item 5): --init is 0-based pixels (README and
--help say so); --init-gt reads a dataset's ground truth in its own convention; pasting OTB's first
line (1-based) as --init gets a note with the 0-based box."""


from cli_helpers import run
from path_helpers import ROOT
from vistrack.io.clips import read_groundtruth_csv


def test_help_and_readme_say_init_is_0_based_pixels():
    _, out, _ = run(["run", "--help"])
    text = " ".join(out.split())
    assert "x,y,w,h in 0-based pixels" in text and "in its dataset's own convention" in text
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert "`--init x,y,w,h` is in 0-based pixels" in readme


def test_init_gt_reads_otb_1_based_and_a_pasted_first_line_gets_a_note(tmp_path):
    from clip_helpers import otb_clip  # img/ and a 1-based groundtruth_rect.txt, as OTB writes it

    truth = otb_clip(tmp_path / "sq", 6)
    code, _, err = run(["run", tmp_path / "sq", "--init-gt", "-n", "50", "--track", tmp_path / "gt.csv"])
    assert code == 0 and "note: --init" not in err, err
    first = read_groundtruth_csv(tmp_path / "gt.csv")
    # the estimate of frame 0 starts from the 0-based box: the square's centre, 30,30
    assert abs(first["cx"][0] - (truth[0, 0] + 10)) < 1.5 and abs(first["cy"][0] - 30) < 1.5
    pasted = "21,21,20,20"  # the file's first line
    code, _, err = run(["run", tmp_path / "sq", "--init", pasted, "-n", "50", "--track", tmp_path / "p.csv"])
    assert code == 0, err
    assert (f"note: --init 21,21,20,20 is the first box of {tmp_path / 'sq' / 'groundtruth_rect.txt'}, which counts "
            "pixels from 1 (OTB, LaSOT); --init is 0-based (the top-left pixel is 0,0), where that box is "
            "20,20,20,20: --init-gt starts from it") in err
    code, _, err = run(["run", tmp_path / "sq", "--init", "20,20,20,20", "-n", "50", "--track", tmp_path / "z.csv"])
    assert code == 0 and "note: --init" not in err, err
