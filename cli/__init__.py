"""The ``rgbt`` command line (installed as ``rgbt_cli``): thin click commands over the library."""
