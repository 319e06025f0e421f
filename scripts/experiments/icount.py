#!/usr/bin/env python3
"""Instructions the CPU megakernel executes in a small render, counted by callgrind: exact and
repeatable whatever else the machine does, unlike its time (kernel_blocks.py splits the same
count by block). Prints the count of the megakernel's object (every function in it: the
work-group function, mega_chunk_start, ...) and of the work-group function alone.

    python3 scripts/experiments/icount.py target/peers/bunnies-room-lambert.glb
    PENUMBRA_CL_OPTIONS=-DMEGA_SLOTS=24 python3 scripts/experiments/icount.py SCENE [SIZE]

A SIZE² render (32 by default) at 16 spp, 6 bounces, one thread; the kernels are built natively
first (PENUMBRA_KERNEL_DIR and PENUMBRA_CL_OPTIONS pass through). About two minutes.
"""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import kernel_blocks as kb  # noqa: E402


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)

    class Args:
        penumbra = "target/release/penumbra"
        scene = sys.argv[1]
        bounces = 6

    size = int(sys.argv[2]) if len(sys.argv) > 2 else 32
    work = tempfile.mkdtemp(prefix="icount-")
    env = dict(os.environ, POCL_CACHE_DIR=os.path.join(work, "pocl"))
    info = kb.render(Args, env, size, 16, os.path.join(work, "warm.exr"))
    if "lanes_load" in info:
        env["PENUMBRA_LANES_LOAD"] = info["lanes_load"]
    env["POCL_MAX_PTHREAD_COUNT"] = "1"
    cg = os.path.join(work, "callgrind.out")
    kb.render(Args, env, size, 16, os.path.join(work, "small.exr"),
              wrap=("valgrind", "--tool=callgrind", "--dump-instr=yes",
                    f"--callgrind-out-file={cg}"))
    so, counts = kb.callgrind_counts(cg)
    if so is None:
        sys.exit("icount: callgrind saw no megakernel.so (is the scene's kernel the megakernel?)")
    workgroup = dict(kb.disassembly(so))
    wg = sum(n for off, n in counts.items() if off in workgroup)
    print(f"{Args.scene}: megakernel.so {sum(counts.values()):,} instructions, "
          f"work-group function {wg:,}")


if __name__ == "__main__":
    main()
