"""`vinadv transpath import-weights`: the TransPath authors' weights (`cf.pth`, `focal.pth`) as vinadv weights."""

from __future__ import annotations

import argparse

from vinadv.commands import add_actions
from vinadv.commands.train_options import (
    add_import_arguments,
    save_import,
    start_import,
)
from vinadv.planners.weights import weights_checksum

#: the format of the record of an import, in the weights file and beside it
IMPORT_RECORD_FORMAT = "vinadv.transpath-import/1"


def register(subparsers) -> None:
    sub = add_actions(subparsers, "transpath", help="the TransPath planners: import the authors' weights")
    imp = sub.add_parser(
        "import-weights",
        help="the TransPath authors' state dict (cf.pth or focal.pth) as vinadv weights, with its record",
    )
    imp.add_argument("weights", metavar="FILE", help="the authors' weights file (weights/cf.pth or weights/focal.pth)")
    imp.add_argument(
        "--mode",
        required=True,
        choices=("cf", "f"),
        help="which model the file holds: cf (correction factors, planner transpath-cf) or f (focal values, "
        "planner transpath-focal); both have the same keys, so the file cannot say",
    )
    add_import_arguments(imp, "FILE", "file")
    imp.set_defaults(func=cmd_import_weights)


def cmd_import_weights(args: argparse.Namespace) -> int:
    from vinadv.planners.transpath.checkpoint import from_authors_state_dict
    from vinadv.planners.transpath.model import save_transpath
    from vinadv.planners.transpath.planner import MOVES, NAMES

    out, license_path = start_import(args, args.weights, "weights", {"FILE": args.weights})
    model = from_authors_state_dict(args.weights, args.mode)
    record = {
        "format": IMPORT_RECORD_FORMAT,
        "planner": NAMES[args.mode],
        "mode": args.mode,
        "imported_from": {"path": args.weights, "sha256": weights_checksum(args.weights), "source": args.source},
        "size": 64,
        "moves": MOVES,
        "corner_cutting": True,
    }
    return save_import(
        args,
        model,
        out,
        record,
        save_transpath,
        f"TransPath ({args.mode}) from {args.weights}; use --planner {NAMES[args.mode]} --weights {out}",
        license_path,
    )
