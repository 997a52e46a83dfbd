"""``embodichain decompose PATH``: convex decomposition of a mesh or of every mesh of a URDF.

Runs :func:`embodichain_core.sim.scene_build.convex.collision_parts` (coacd, cached on disk) and prints one
row per mesh: components, convex components, hulls, whether the result came from the cache, time.

Example:
    $ embodichain decompose mug.ply --max-hulls 8
    $ embodichain decompose SlidingBoxDrawer/SlidingBoxDrawer.urdf --cache-dir /tmp/coacd
"""

from __future__ import annotations

import argparse
import os
import sys

DESCRIPTION = "Convex decomposition (coacd, cached) of a mesh file or of every mesh of a URDF."


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add this command's arguments to ``parser`` (used by the top-level CLI too)."""
    parser.add_argument("path", help="mesh file (.ply/.obj/.stl/.glb/...) or .urdf; data names are resolved")
    parser.add_argument(
        "--max-hulls",
        type=int,
        default=8,
        dest="max_hulls",
        help="most convex hulls per non-convex component (default: 8)",
    )
    parser.add_argument(
        "--cache-dir", default=None, dest="cache_dir", help="coacd cache folder (default: $EMBODICHAIN_CACHE_DIR/coacd)"
    )
    return parser


def build_parser() -> argparse.ArgumentParser:
    """The stand-alone parser of ``embodichain decompose``."""
    return add_arguments(argparse.ArgumentParser(prog="embodichain decompose", description=DESCRIPTION))


def run(args: argparse.Namespace) -> int:
    """Decompose ``args.path`` and print the report table; 0 on success, 1 on error."""
    from embodichain_core.sim.scene_build.convex import decompose_file
    from embodichain_core.sim.data import get_data_path

    try:
        path = args.path if os.path.exists(args.path) else get_data_path(args.path)
        report = decompose_file(path, max_convex_hull_num=args.max_hulls, cache_dir=args.cache_dir)
    except (OSError, ValueError) as exc:
        print(f"embodichain decompose: error: {exc}", file=sys.stderr)
        return 1
    print(f"{report.path} (max hulls per component: {args.max_hulls})")
    print(report.format_table() if report.rows else "no meshes found")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point: parse ``argv`` (default ``sys.argv[1:]``) and run."""
    return run(build_parser().parse_args(argv))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
