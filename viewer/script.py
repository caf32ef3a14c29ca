"""What every script that records its results shares, written once so that an example reads as
its mechanism: its ``main`` checks the recording before computing
(:func:`check_recording_first`), and its command line takes ``--rrd`` and ``--show``
(:func:`run_script`)."""

from __future__ import annotations

import argparse
import functools
import inspect
from typing import Any, Callable, Mapping

from mbd3d.errors import MBDError
from mbd3d.viewer.recorder import check_destination

__all__ = ["run_script", "check_recording_first"]


def check_recording_first(main: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate a script's ``main(..., rrd=None, show=False)`` so that the recording's path
    (and a display, with ``show``) is checked before it computes anything: a mistake fails at
    once, not after the computing (see :func:`mbd3d.viewer.check_destination`).

    Parameters
    ----------
    main : callable
        The script's ``main``, with ``rrd`` and ``show`` parameters.
    """
    signature = inspect.signature(main)

    @functools.wraps(main)
    def checked(*args: Any, **kwargs: Any) -> Any:
        arguments = signature.bind(*args, **kwargs)
        arguments.apply_defaults()
        if arguments.arguments.get("rrd") is not None:
            check_destination(arguments.arguments["rrd"],
                              show=bool(arguments.arguments.get("show", False)))
        return main(*args, **kwargs)
    return checked


def run_script(main: Callable[..., Any], description: str, rrd: str,
               options: Mapping[str, Mapping[str, Any]] | None = None,
               argv: list[str] | None = None) -> Any:
    """Run ``main`` from a script's command line: ``--rrd FILE`` (default ``rrd``), ``--show``
    and the script's own ``options``, each passed to ``main`` by its name.

    mbd3d's errors (a recording that cannot be written, no display for ``--show``, ...) end
    the script with their message and exit status 1, not a traceback.

    Parameters
    ----------
    main : callable
        Called as ``main(rrd=..., show=..., **options)``.
    description : str
        The script's docstring; its first paragraph (its first sentence or sentences, up to a
        blank line) is the ``--help`` description, whole.
    rrd : str
        The default recording file.
    options : mapping, optional
        Flag -> keyword arguments of :meth:`argparse.ArgumentParser.add_argument`, e.g.
        ``{"--duration": {"type": float, "default": 10.0, "help": "simulated time [s]"}}``.
    argv : list of str, optional
        The arguments (default the command line's).

    Returns
    -------
    What ``main`` returns.
    """
    first = description.strip().split("\n\n")[0]
    parser = argparse.ArgumentParser(description=" ".join(first.split()))
    for flag, keywords in (options or {}).items():
        parser.add_argument(flag, **keywords)
    parser.add_argument("--rrd", default=rrd, help="the Rerun recording to write")
    parser.add_argument("--show", action="store_true", help="open it in the Rerun viewer")
    arguments = vars(parser.parse_args(argv))
    try:
        return main(**arguments)
    except MBDError as error:  # a bad path, no display, ...: the message says what to do
        raise SystemExit(f"error: {error}") from None
