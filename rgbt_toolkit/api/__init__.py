"""The public Python API, re-exported at the package root (``rgbt_toolkit.track`` ...); see ``docs/api.md``.

One function or class per CLI job, built from the same library pieces the commands call, so Python and the command
line give the same results: :func:`~rgbt_toolkit.api.tracking.track`, :class:`~rgbt_toolkit.api.tracking.Tracker`,
:func:`~rgbt_toolkit.api.images.register`, :func:`~rgbt_toolkit.api.images.load_calibration`,
:func:`~rgbt_toolkit.api.images.fuse`, :func:`~rgbt_toolkit.api.images.fusion_metrics`,
:func:`~rgbt_toolkit.api.scores.evaluate`.
"""

EXPORTS = {
    "FrameRecord": "frames",
    "TrackResult": "tracking",
    "Tracker": "tracking",
    "evaluate": "scores",
    "fuse": "images",
    "fusion_metrics": "images",
    "load_calibration": "images",
    "register": "images",
    "track": "tracking",
}
