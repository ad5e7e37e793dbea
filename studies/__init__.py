"""Study code beside the benchmarks: derivations, seed checks, reference maps and
synthetic measurements that the benchmarks, the documentation's tables and the tests
use. Not installed with gonio (it may need the ``test`` extra, e.g. mpmath); import it
from the repository root (``python -m studies.brdf.examples``, pytest, benchmarks/)."""
