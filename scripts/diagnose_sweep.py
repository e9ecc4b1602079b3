"""What the diagnosis sweeps (scripts/planted_benchmark.py, scripts/motion_sweep.py) share:
the binary they run, a quiet subprocess, the times they record and their command line
(`run OUT [...] [-- DIAGNOSE FLAGS]`, `score OUT`)."""
import argparse
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def binary():
    """The release build, or the binary SAWTOOTH_BIN names (a build kept for a long run)."""
    return os.environ.get("SAWTOOTH_BIN") or os.path.join(ROOT, "target", "release", "sawtooth")


def sh(args, log=None):
    with open(log, "w") if log else open(os.devnull, "w") as err:
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=err, cwd=ROOT)


def record_time(out, name, start):
    """`name`'s wall time since `start` (and the load) in OUT/times.txt and on stderr."""
    with open(os.path.join(out, "times.txt"), "a") as t:
        t.write(f"{name} {time.time() - start:.0f} s wall (load {open('/proc/loadavg').read().split()[0]})\n")
    print(f"{name}: {time.time() - start:.0f} s", file=sys.stderr, flush=True)


def main(doc, run, score, run_arguments):
    """Parse `run OUT ... [-- FLAGS]` (the flags go to `sawtooth diagnose`, as `args.flags`)
    or `score OUT` and call `run` or `score`; `run_arguments(parser)` adds run's options."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("out")
    run_arguments(r)
    s = sub.add_parser("score")
    s.add_argument("out")
    argv = sys.argv[1:]
    flags = argv[argv.index("--") + 1:] if "--" in argv else []
    a = p.parse_args(argv[: argv.index("--")] if "--" in argv else argv)
    a.flags = flags
    if a.command == "run":
        run(a)
    else:
        score(a)
