"""g1patch's benchmarks: ``python -m benchmarks`` runs them (:mod:`benchmarks.__main__`),
``python -m benchmarks.report`` puts their figures into the README (:mod:`benchmarks.report`);
each ``bench_*.py`` also runs alone, and :mod:`benchmarks.harness` is what they share."""
