"""`python -m bench`: the solve-only accuracy-vs-time sweep against Cycles and exact answers, and
the dissertation's Table 5.1 (`make bench`, `make bench-quick`; run from the repository root)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .run import run_bench


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smaller sweep: a few minutes on 2 cores")
    parser.add_argument("--output-dir", required=True, metavar="DIR",
                        help="writes accuracy_vs_time.{json,md,png} and table_5_1.{json,md}")
    parser.add_argument("--cache-dir", metavar="DIR", help="Cycles reference cache (default DIR/cache)")
    parser.add_argument("--table51-samples", type=int, default=None, metavar="N",
                        help="timed solves per solver and size for Table 5.1 (default 30, quick 5; 0 skips)")
    parser.add_argument("--scenes", default="cornell-box,furnace,plates",
                        help="comma-separated: cornell-box (Cycles reference), furnace, plates (exact)")
    args = parser.parse_args(argv)
    run_bench(Path(args.output_dir), args.quick, args.cache_dir, args.table51_samples,
              tuple(name for name in args.scenes.split(",") if name))
    return 0


if __name__ == "__main__":
    sys.exit(main())
