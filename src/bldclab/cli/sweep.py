"""``bldclab sweep``: run a sweep file into its resumable store, optionally exporting a CSV."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._files import write_atomic
from ..errors import BldclabError
from ..sweep import Dask, Executor, Processes, Serial, Sweep, run
from .common import positive_int
from .paths import check_out_file

__all__ = [
    "configure_command",
    "run_command",
]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab sweep``."""
    p.add_argument("sweep", metavar="SWEEP.toml", type=Path, help="sweep file (format: docs/sweeps.md)")
    p.add_argument("--store", metavar="DIR|FILE", type=Path,
                   help="results store: an SQLite file, or a directory to hold SWEEP.sqlite "
                   "(default: SWEEP.sqlite next to the sweep file); finished cases in it are not run again")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", metavar="N", type=positive_int,
                       help="local worker processes (default: one per core)")
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on this Dask cluster")
    where.add_argument("--serial", action="store_true", help="run in this process, one case after the other")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--csv", metavar="OUT.csv", type=Path,
                   help="also write the results (one row per case, axes as columns) to this CSV file")


def _store_path(sweep_file: Path, store: Path | None) -> Path:
    if store is None:
        return sweep_file.with_suffix(".sqlite")
    if store.is_dir():
        return store / f"{sweep_file.stem}.sqlite"
    if not store.parent.is_dir():
        raise BldclabError("--store", f"directory {str(store.parent)!r} does not exist")
    return store


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab sweep``: exit 0 when every case is stored, 1 if some failed, 2 for bad input."""
    sw = Sweep.from_toml(args.sweep)
    path = _store_path(args.sweep, args.store)
    if args.csv is not None and not args.csv.parent.is_dir():
        raise BldclabError("--csv", f"directory {str(args.csv.parent)!r} does not exist")
    check_out_file(args.csv, "--csv")
    executor: Executor
    if args.serial:
        executor = Serial()
    elif args.scheduler:
        executor = Dask(args.scheduler)
    else:
        executor = Processes(args.workers)
    done = run(sw, path, executor=executor, progress=False if args.no_progress else None)
    with done.store:
        sys.stdout.write(done.summary() + "\n")
        if args.csv is not None:
            df = done.to_pandas()
            write_atomic(args.csv, df.to_csv(index=False, lineterminator="\n").encode(), "--csv")
            sys.stdout.write(f"wrote {args.csv} ({len(df)} rows)\n")
    if done.failed:
        index, message = done.errors[0]
        sys.stderr.write(f"bldclab: error: {done.failed} of {done.total} cases failed (rerun retries them); "
                         f"first: case {index}: {' '.join(message.split())}\n")
        return 1
    return 0
