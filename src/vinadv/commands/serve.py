"""`vinadv serve`: the browser viewer and annotation tool over a results database."""

from __future__ import annotations

import argparse
import logging
import os
import socket

from vinadv.commands import add_db_argument
from vinadv.commands.output import add_output_options, is_quiet, note
from vinadv.errors import InputError, OutputError


def register(subparsers) -> None:
    serve = subparsers.add_parser(
        "serve",
        help="browse runs and map pairs in a web browser, and label pairs by hand",
        description="Serve the viewer: runs with their category counts and harmful rate, a pair grid with "
        "thumbnails to filter and sort by label, harm, regret and search effort, pair pages with both maps, paths, "
        "the search's expanded cells and the path image, the robustness benchmarks, (--bench) a leaderboard, "
        "and labelling (keys f/d/u/c = FP/DP/UrP/UcP, n/p = next/previous). Human labels go to the annotations "
        "table, beside the automatic ones. Binds to "
        "127.0.0.1; there is no login, so serving other addresses needs --allow-remote.",
    )
    add_db_argument(serve)
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    serve.add_argument("--port", type=int, default=8000, help="port (default 8000)")
    serve.add_argument(
        "--allow-remote",
        action="store_true",
        help="allow binding a non-loopback address (anyone who can reach it can label pairs)",
    )
    serve.add_argument(
        "--bench",
        metavar="DIR",
        default=None,
        help="a folder of benchmark entries (`vinadv bench run --out`, e.g. docs/results/bench) whose leaderboard "
        "the page /bench shows (default: none, no bench page)",
    )
    add_output_options(serve, quiet=True)
    serve.set_defaults(func=cmd_serve)


def check_bind(host: str, port: int, allow_remote: bool) -> None:
    """Refuse (InputError) a port out of range, or a non-loopback host without `allow_remote`."""
    from vinadv.viewer.app import is_loopback

    if not 1 <= port <= 65535:
        raise InputError(f"--port: must be 1 to 65535, got {port}")
    if not host:
        raise InputError("--host: must not be empty")
    if not allow_remote and not is_loopback(host):
        raise InputError(
            f"--host {host}: refusing to serve on a non-loopback address; the viewer has no login and anyone "
            "who reaches it can label pairs. Pass --allow-remote to do it anyway."
        )


def cmd_serve(args: argparse.Namespace) -> int:
    check_bind(args.host, args.port, args.allow_remote)
    if args.bench is not None and not os.path.isdir(args.bench):
        raise InputError(f"--bench {args.bench}: no such folder")
    try:
        from werkzeug.serving import make_server

        from vinadv.viewer.app import create_app
    except ImportError as exc:  # Flask is the `viewer` extra
        raise InputError(f"vinadv serve needs Flask: pip install 'vinadv[viewer]' ({exc})") from None
    from vinadv.store import Store

    try:
        store = Store.open(args.db, create=False)
        try:
            created = store.ensure_indexes()
        except OutputError:
            store.close()
            raise
    except OutputError:  # a database the user may only read: browse it, labelling is off
        store, created = Store.open(args.db, readonly=True), []
        note(args, f"database {store.url} is read-only: browsing only, labels cannot be stored")
    if created:
        note(args, f"created indexes {', '.join(created)} (once per database)")
    app = create_app(store, allow_remote=args.allow_remote, bench_dir=args.bench)
    # import the image renderers now (matplotlib; torch behind vinadv.classify), not on the first pair page
    import vinadv.classify.images  # noqa: F401
    import vinadv.plot.maps  # noqa: F401

    # bind here rather than in werkzeug, which prints and calls sys.exit(1) when the port is taken
    family = socket.AF_INET6 if ":" in args.host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((args.host.strip("[]"), args.port))
        sock.listen(128)
        server = make_server(args.host, args.port, app, threaded=True, fd=sock.fileno())
        port = sock.getsockname()[1]
    except OSError as exc:
        store.close()
        raise InputError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}") from None
    finally:
        sock.close()  # the server holds its own duplicate of the socket
    if is_quiet(args):  # the request log
        logging.getLogger("werkzeug").setLevel(logging.ERROR)
    host = f"[{args.host}]" if ":" in args.host else args.host
    print(f"vinadv viewer on http://{host}:{port}/ ({store.url}); Ctrl-C stops it", flush=True)
    try:
        server.serve_forever()
    finally:
        server.server_close()
        store.close()
    return 0
