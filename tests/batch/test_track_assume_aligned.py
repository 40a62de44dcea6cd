"""``rgbt batch track --assume-aligned``: the flag reaches the video-pair tracker and is part of the job's identity."""

from __future__ import annotations

from pathlib import Path

import pytest

from rgbt_toolkit.batch.items import Item
from rgbt_toolkit.batch.tasks import TrackerSpec, TrackJob, track_item

CALLS: list[dict] = []


def recording_video_fn(rgb_path, t_path, out_dir, preset, **options) -> dict[str, Path]:
    """A video-pair tracker that records the options it was given and writes one file."""
    CALLS.append(options)
    target = Path(out_dir) / "boxes_rgb.txt"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text("1,2,3,4\n")
    return {"boxes_rgb": target}


def plain_video_fn(rgb_path, t_path, out_dir, preset) -> dict[str, Path]:
    """A custom tracker written before the flag existed: it must keep working without it."""
    return recording_video_fn(rgb_path, t_path, out_dir, preset)


@pytest.mark.parametrize("aligned", [False, True])
def test_flag_reaches_the_video_tracker_only_when_given(tmp_path, aligned):
    CALLS.clear()
    fn = "recording_video_fn" if aligned else "plain_video_fn"
    job = TrackJob(tmp_path, TrackerSpec(None, f"{__name__}:{fn}"), "default", assume_aligned=aligned)
    item = Item("pair", "video_pair", (str(tmp_path / "a_rgb.mp4"), str(tmp_path / "a_t.mp4")))
    written = track_item(item, job)
    assert written == [str(tmp_path / "pair" / "boxes_rgb.txt")]
    assert CALLS == [{"assume_aligned": True} if aligned else {}]


def test_assume_aligned_is_part_of_the_job_signature(tmp_path):
    spec = TrackerSpec("m:seq", "m:video")
    plain, aligned = TrackJob(tmp_path, spec), TrackJob(tmp_path, spec, assume_aligned=True)
    assert plain.signature() == "track:m:seq|m:video:default"  # unchanged: earlier manifests still resume
    assert aligned.signature() != plain.signature()


def test_jmmac_video_pair_without_registration_fails_the_item(tmp_path):
    """The real tracker: a pair that cannot be registered raises (a failed item), never tracks on a guess."""
    import numpy as np

    from rgbt_toolkit.errors import RegistrationError
    from rgbt_toolkit.io.video import write_video
    from rgbt_toolkit.jmmac.api import track_video_pair

    write_video(tmp_path / "n_rgb.mp4", [np.full((48, 64, 3), 5, np.uint8)] * 4, fps=10)
    write_video(tmp_path / "n_t.mp4", [np.full((48, 64, 3), 40, np.uint8)] * 4, fps=10)
    with pytest.raises(RegistrationError, match="--assume-aligned"):
        track_video_pair(tmp_path / "n_rgb.mp4", tmp_path / "n_t.mp4", tmp_path / "out", "B-T")
    assert not (tmp_path / "out").exists()
