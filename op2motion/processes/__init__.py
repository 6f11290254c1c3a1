"""The program's processes: worker pools that end with their parent (:mod:`.workers`), numba kernels compiled by
one process at a time (:mod:`.compiled`), and Ctrl-C and SIGTERM held for a moment that must not be cut
(:mod:`.interrupts`). Nothing here imports the rest of op2motion."""
