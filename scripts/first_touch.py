#!/usr/bin/env python3
"""What the first touch of new memory costs on this machine, GiB by GiB.

A process's new pages are zeroed by the kernel when first written; on a virtual machine the host may
also have to back them. `hooke bench scale` spends most of a big cloth's load there, so this probe
tells its figures apart from hooke's own work: it maps --gib GiB of anonymous memory and writes one
byte per 4 KiB page, timing each GiB.

    scripts/first_touch.py --gib 4

Standard library only; Linux (or any system with anonymous mmap).
"""

import argparse
import mmap
import time

GIB = 1 << 30
PAGE = 4096


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--gib", type=int, default=4, help="GiB to touch (default 4)")
    a = p.parse_args()
    if a.gib < 1:
        p.error("--gib must be at least 1")
    m = mmap.mmap(-1, a.gib * GIB, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    print("GiB  first touch (s)")
    for g in range(a.gib):
        start = time.perf_counter()
        for off in range(g * GIB, (g + 1) * GIB, PAGE):
            m[off] = 1
        print(f"{g + 1:3d}  {time.perf_counter() - start:.2f}", flush=True)
    m.close()


if __name__ == "__main__":
    main()
