"""``saltation paper``: the figures of *Fold bifurcations in discontinuous systems* with their data
(:mod:`saltation.apps.paper`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from saltation.apps.cli.options import add_no_progress, add_out, check_out_dir, positive
from saltation.apps.cli.text import paragraph, progress_bar, special_points_text

#: The smallest ``--ds-max`` of ``saltation paper``: each of its branches has at most 5000 points, and
#: Fig. 7's stable branch takes about 3300 of them at a largest step of 0.002.
PAPER_MIN_DS_MAX = 2e-3


def cmd_paper(args: argparse.Namespace) -> int:
    """``saltation paper``: reproduce Figures 3, 4, 6 and 7 with their data."""
    from saltation.apps import paper

    check_out_dir(args.out)
    settings = paper.PaperSettings(ds=args.ds_max, ds_max=args.ds_max)
    update, close = progress_bar(not args.no_progress)
    try:
        results = paper.compute(settings, progress=update)
    finally:
        close()
    written = paper.write(results, Path(args.out))
    print(special_points_text(results.special_point_records()))
    if results.smoothing:
        print()
        print("the block-on-belt model smoothed (saltation.model.regularize), its stable branch followed in forward time:")
        print(paper.smoothing_table(results.smoothing))
    print(f"{len(written)} files written to {args.out}: figures fig3, fig4, fig6, fig7, fig8 (PNG and PDF), branch "
          "data (JSON; CSV, each with its .meta.json), the phase plane's curves (NPZ), special_points.json and "
          "smoothing_table.json")
    return 0


def add_parser(sub) -> None:
    """The parser of ``saltation paper``."""
    p = sub.add_parser(
        "paper",
        help="reproduce Figures 3, 4, 6 and 7 of 'Fold bifurcations in discontinuous systems'",
        description=paragraph(
            """Compute the response curve of the trilinear spring system (Figs. 3 and 4: corners at
            w_A and w_B, the discontinuous fold at w_B, the smooth fold of the hardened peak), the
            phase plane of the block-on-belt system (Fig. 6) and its bifurcation diagram with the
            infinitely unstable branch found by backward-time shooting (Fig. 7). Writes the figures
            (PNG and PDF), the branch data (JSON and CSV) and DIR/special_points.json, and prints the
            located special points."""
        ),
    )
    add_out(p, "output directory", default=None, required=True)
    p.add_argument(
        "--ds-max", metavar="S", default=0.015,
        type=positive("--ds-max", PAPER_MIN_DS_MAX, " (a branch of the paper has at most 5000 points)"),
        help=f"largest continuation step: smaller gives denser diagrams (default 0.015, about 400 points in Fig. 3; "
             f"at least {PAPER_MIN_DS_MAX:g})",
    )
    add_no_progress(p)
    p.set_defaults(handler=cmd_paper)
