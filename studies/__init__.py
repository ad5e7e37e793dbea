"""Study code beside the speed benchmarks: the accuracy study scripts at the top
(``python studies/<name>.py``, each writing its results page through
benchmarks/_report.py), and below them derivations, seed checks, reference maps and
synthetic measurements that the studies, the benchmarks, the documentation's tables and
the tests use. Not installed with gonio (it may need the ``test`` extra, e.g. mpmath);
import it from the repository root (``python -m studies.brdf.examples``, pytest)."""
