"""Wall time of each command of the README's "First five minutes", as a new user runs it.

Reads the README's first ``bash`` block after the heading "## First five minutes", runs
every ``fsicas ...`` line (but the explorer's server) in a fresh temporary folder (the files it writes land there;
``examples/`` is linked into it),
one after the other, and prints a Markdown table: the command, its exit status and its
wall time in seconds, with the machine's core count and load average before the run.
The compiled-code caches are the user's own (warm after the first run of a command).

    python3 benchmarks/readme_commands.py            # about 10 minutes on 2 idle cores
    python3 benchmarks/readme_commands.py --only onset,eig
"""
from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Commands that serve until stopped, not timed.
SERVERS = {"fsicas explore"}


def readme_commands(readme: Path = ROOT / "README.md") -> list[str]:
    """The ``fsicas`` command lines of the README's "First five minutes" block."""
    text = readme.read_text()
    section = text.split("## First five minutes", 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    lines = [line.split("#", 1)[0].strip() for line in block.splitlines()]
    return [line for line in lines if line.startswith("fsicas ") and line not in SERVERS]


def timed(command: str, folder: Path) -> tuple[int, float]:
    """Exit status and wall time (s) of ``command`` run in ``folder``."""
    start = time.perf_counter()
    done = subprocess.run(shlex.split(command), cwd=folder, stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL, env={**os.environ, "MPLBACKEND": "Agg"})
    return done.returncode, time.perf_counter() - start


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", help="comma-separated subcommands to run (default: all)")
    args = parser.parse_args(argv)
    commands = readme_commands()
    if args.only:
        wanted = set(args.only.split(","))
        commands = [c for c in commands if c.split()[1] in wanted]
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} before the run, "
          f"Python {sys.version.split()[0]}\n")
    print("| command | exit | wall time (s) |\n| --- | --- | --- |")
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "examples").symlink_to(ROOT / "examples")   # the inputs it names
        for command in commands:
            code, seconds = timed(command, Path(folder))
            print(f"| `{command}` | {code} | {seconds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
