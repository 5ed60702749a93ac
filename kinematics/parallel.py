"""One lock for every launch of a ``parallel=True`` numba kernel.

numba's ``workqueue`` threading layer (the one used when neither OpenMP's ``libgomp`` nor TBB is
installed, e.g. in a slim container) aborts the whole process when two Python threads launch
parallel kernels at once -- and the explorer and the REST API run jobs on several threads. Each
launch already uses every core, so holding this lock for the (short, chunked) launches costs no
throughput and makes the core safe under any threading layer.
"""

from __future__ import annotations

import threading

KERNEL_LOCK = threading.Lock()
