"""Research campaigns built on the package and kept out of it (the package never imports them); run from the
repository root (``PYTHONPATH=$PWD``).  ``atlas_run``: one point of the error atlas, and the atlas assembled from
its points (the campaign script: ``benchmarks/error_atlas.py``; its product, ``screening/data/error_atlas.nc``, is
what the package reads)."""
