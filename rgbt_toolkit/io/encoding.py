"""x264 settings that the video writers and the command line share; kept free of heavy imports so the CLI can
offer them without loading PyAV."""

from __future__ import annotations

# x264's speed presets, fastest first: each step slower encodes a smaller file of the same quality (crf)
X264_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow")
CRF_RANGE = (0, 51)  # x264's constant rate factor: 0 is lossless, 51 the smallest file
