#!/usr/bin/env python3
"""Where the CPU megakernel's time goes, block by block: instructions against time.

PoCL inlines the whole megakernel into one function, so a profiler's per-function view says
nothing and its per-instruction view is 7,000 lines. This script joins two measurements of
the same compiled kernel (one PoCL cache):

- callgrind (valgrind) counts how often each instruction runs, in a small render on one
  thread: exact and repeatable, unlike the time on a shared machine;
- perf samples where the time goes (cpu-clock), in a larger render on one thread.

Instructions that run equally often form a block (a loop body, a branch's side), so
grouping by execution count splits the kernel into its parts: the node step, the pair
tests, shading, the pops... For each block it prints its share of the instructions, its
share of the time and their ratio (above 1: slower than the kernel's average instruction,
a stall: a cache miss, a mispredicted branch, a store-to-load forwarding failure).

    python3 scripts/experiments/kernel_blocks.py target/peers/bunnies-room-lambert.glb
    PENUMBRA_CL_OPTIONS=-DLANES_LEAF_MIN=2 python3 scripts/experiments/kernel_blocks.py SCENE

Needs valgrind, perf and objdump; runs target/release/penumbra (PENUMBRA_KERNEL_DIR and
PENUMBRA_CL_OPTIONS pass through, so a kernel variant is measured without a rebuild). The
small render takes about two minutes under callgrind. docs/benchmarks.md, "Twenty-fourth
session", has what it found.
"""

import argparse
import collections
import json
import os
import re
import subprocess
import sys
import tempfile

WORKGROUP = "_pocl_kernel_megakernel_workgroup"


def render(args, env, size, spp, out, wrap=()):
    cmd = [*wrap, args.penumbra, "render", args.scene, "-o", out, "--spp", str(spp),
           "--width", str(size), "--height", str(size), "--bounces", str(args.bounces),
           "--no-russian-roulette", "--hard-shadows", "--device", "cpu"]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"kernel_blocks: {' '.join(cmd[:3])}... failed: {r.stderr.strip()[-300:]}")
    lines = [line for line in r.stdout.splitlines() if line.startswith("{")]
    return json.loads(lines[-1]) if lines else {}


def callgrind_counts(path):
    """Executions of each instruction of the megakernel's object, by offset in the file."""
    names, counts = {}, collections.Counter()
    in_kernel, skip, addr = False, False, 0
    with open(path) as f:
        for line in f:
            m = re.match(r"^c?ob=\((\d+)\)\s*(\S*)", line)
            if m:
                if m.group(2):
                    names[m.group(1)] = m.group(2)
                if line.startswith("ob="):
                    in_kernel = names.get(m.group(1), "").endswith("megakernel.so")
                continue
            if line.startswith("calls="):
                skip = True  # the next cost line is the call's inclusive cost
                continue
            m = re.match(r"^(0x[0-9a-f]+|[+-]\d+|\*)\s+\S+\s+(\d+)", line)
            if not m:
                continue
            a = m.group(1)
            if a.startswith("0x"):
                addr = int(a, 16)
            elif a[0] in "+-":
                addr += int(a)
            if skip:
                skip = False
            elif in_kernel:
                counts[addr] += int(m.group(2))
    so = next((n for n in names.values() if n.endswith("megakernel.so")), None)
    return so, counts


def disassembly(so):
    """(offset, text) of each instruction of the work-group function."""
    out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", so], capture_output=True,
                         text=True, check=True).stdout
    insns, inside = [], False
    for line in out.splitlines():
        m = re.match(r"^([0-9a-f]+) <(.*)>:", line)
        if m:
            inside = m.group(2) == WORKGROUP
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+(.*)$", line)
        if inside and m:
            insns.append((int(m.group(1), 16), m.group(2).strip()))
    return insns


def perf_samples(data, so):
    """Samples at each offset of the work-group function."""
    base = None
    for line in subprocess.run(["nm", so], capture_output=True, text=True).stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == WORKGROUP:
            base = int(parts[0], 16)
    out = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,symoff"],
                         capture_output=True, text=True).stdout
    samples = collections.Counter()
    for line in out.splitlines():
        m = re.search(WORKGROUP + r"\+0x([0-9a-f]+)", line)
        if m and base is not None:
            samples[base + int(m.group(1), 16)] += 1
    return samples


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("--penumbra", default="target/release/penumbra")
    p.add_argument("--small", type=int, default=32, help="image side of the callgrind render")
    p.add_argument("--large", type=int, default=256, help="image side of the perf render")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--bounces", type=int, default=6)
    p.add_argument("--blocks", type=int, default=25, help="blocks listed, most time first")
    args = p.parse_args()
    work = tempfile.mkdtemp(prefix="kernel-blocks-")
    env = dict(os.environ, POCL_CACHE_DIR=os.path.join(work, "pocl"))
    # The kernels are built natively first (under valgrind the build would take an hour) and
    # the lanes' load form (by CPU vendor, which valgrind's CPUID hides) is kept.
    info = render(args, env, args.small, args.spp, os.path.join(work, "warm.exr"))
    if "lanes_load" in info:
        env["PENUMBRA_LANES_LOAD"] = info["lanes_load"]
    env["POCL_MAX_PTHREAD_COUNT"] = "1"
    cg = os.path.join(work, "callgrind.out")
    render(args, env, args.small, args.spp, os.path.join(work, "small.exr"),
           wrap=("valgrind", "--tool=callgrind", "--dump-instr=yes",
                 f"--callgrind-out-file={cg}", f"--toggle-collect={WORKGROUP}*"))
    so, counts = callgrind_counts(cg)
    if so is None:
        sys.exit("kernel_blocks: callgrind saw no megakernel.so (is the scene's kernel the megakernel?)")
    data = os.path.join(work, "perf.data")
    render(args, env, args.large, args.spp, os.path.join(work, "large.exr"),
           wrap=("perf", "record", "-q", "-e", "cpu-clock", "-F", "4000", "-o", data))
    samples = perf_samples(data, so)
    built = [os.path.join(d, f) for d, _, fs in os.walk(env["POCL_CACHE_DIR"]) for f in fs
             if f == "megakernel.so"]
    if len(built) != 1:
        sys.exit(f"kernel_blocks: the two renders built {len(built)} megakernels, not one")
    insns = disassembly(so)
    ir, time, size, first = (collections.Counter() for _ in range(4))
    for off, text in insns:
        n = counts.get(off, 0)
        ir[n] += n
        time[n] += samples.get(off, 0)
        size[n] += 1
        if n not in first:
            first[n] = off
    total_ir, total_t = sum(ir.values()) or 1, sum(time.values()) or 1
    print(f"{args.scene}: {total_ir:,} instructions in the work-group function "
          f"({args.small}² × {args.spp} spp), {total_t:,} perf samples ({args.large}²)")
    print(f"{'executions':>11} {'insns':>6} {'% instr':>8} {'% time':>7} {'ratio':>6}  first")
    for n in sorted(time, key=lambda k: -time[k])[: args.blocks]:
        share_i, share_t = ir[n] / total_ir, time[n] / total_t
        ratio = share_t / share_i if share_i else float("inf")
        text = next(t for o, t in insns if o == first[n])
        print(f"{n:>11,} {size[n]:>6} {share_i * 100:>8.2f} {share_t * 100:>7.2f} "
              f"{ratio:>6.2f}  {first[n]:x} {text[:40]}")


if __name__ == "__main__":
    main()
