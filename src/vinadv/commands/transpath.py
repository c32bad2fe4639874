"""`vinadv transpath import-weights`: the TransPath authors' weights (`cf.pth`, `focal.pth`) as vinadv weights."""

from __future__ import annotations

import argparse
from pathlib import Path

from vinadv.commands import add_actions
from vinadv.commands.output import add_output_options
from vinadv.commands.train_options import (
    add_weights_out_argument,
    check_weights_out,
    file_beside,
    import_stamp,
    read_licence,
    save_import,
)
from vinadv.errors import InputError
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
    imp.add_argument(
        "--license",
        default=None,
        help="the licence of the authors' code and weights, copied into the record (default: LICENSE beside FILE, "
        "if there)",
    )
    imp.add_argument(
        "--source", default=None, help="where the file comes from, recorded (say the repository, commit and path)"
    )
    add_weights_out_argument(imp)
    add_output_options(imp, json="the record")
    imp.set_defaults(func=cmd_import_weights)


def cmd_import_weights(args: argparse.Namespace) -> int:
    from vinadv.planners.transpath.checkpoint import from_authors_state_dict
    from vinadv.planners.transpath.model import save_transpath
    from vinadv.planners.transpath.planner import MOVES, NAMES

    out = check_weights_out(args.out, {"FILE": args.weights, "--license": args.license})
    if not Path(args.weights).is_file():
        raise InputError(f"{args.weights}: no such weights file")
    license_path = file_beside(args.weights, args.license, "LICENSE")
    model = from_authors_state_dict(args.weights, args.mode)
    record = {
        "format": IMPORT_RECORD_FORMAT,
        "planner": NAMES[args.mode],
        "mode": args.mode,
        "imported_from": {"path": args.weights, "sha256": weights_checksum(args.weights), "source": args.source},
        "license": read_licence(license_path),
        "size": 64,
        "moves": MOVES,
        "corner_cutting": True,
        **import_stamp(),
    }
    return save_import(
        args,
        model,
        out,
        record,
        save_transpath,
        f"TransPath ({args.mode}) from {args.weights}; use --planner {NAMES[args.mode]} --weights {out}",
    )
