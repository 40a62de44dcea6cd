"""rgbt-toolkit: paired visible (RGB) and thermal (T) video and image processing.

The library half of the product: trackers, fusion, registration, metrics, evaluation and I/O. It never imports the
command-line interface, never prints and never configures logging.
"""

__version__ = "0.1.0"
