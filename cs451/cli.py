"""The ``cs451`` command: parse the line (``cs451/cliargs.py``), run the subcommand (``cs451/commands.py``), and turn
what went wrong into one line and an exit status, as otter-grader's CLI does over the functions the tests and the
Python API call too.

Exit status: 0 success; 1 a grade under ``--fail-under`` or a check that found something; 2 a mistake the user can
fix (the command line, a file it names, where it writes), in one line without a traceback; 3 a bug in the kit.
"""
from __future__ import annotations

import errno
import os
import sys
import traceback
from pathlib import Path

from .cliargs import build_parser
from .errors import KitError

__all__ = ["build_parser", "main"]

#: An OSError with one of these is the user's machine (a path, its permissions, a full or read-only disk), not a bug.
ENVIRONMENT_ERRNOS = {errno.ENOENT, errno.EACCES, errno.EPERM, errno.ENOTDIR, errno.EISDIR, errno.EEXIST,
                      errno.EROFS, errno.ENOSPC, errno.EDQUOT}
#: ... and these need no file name to say so.
DISK_ERRNOS = {errno.EROFS, errno.ENOSPC, errno.EDQUOT}


def environment_error(err: BaseException) -> str | None:
    """The one line for an error of the user's environment (``/x/y: Permission denied``), or None for a kit bug:
    an OSError naming a path that is missing, in the way, not writable, or on a full or read-only disk."""
    if not isinstance(err, OSError) or err.errno not in ENVIRONMENT_ERRNOS:
        return None
    if err.filename is None and err.errno not in DISK_ERRNOS:
        return None
    where = "".join(f"{name}: " for name in (err.filename, err.filename2) if name is not None)
    return f"{where}{err.strerror or err}"


def _joined_values(argv: list[str]) -> list[str]:
    """``--size -5x10`` as ``--size=-5x10``, so that argparse reports the bad size, not a missing one."""
    out: list[str] = []
    for token in argv:
        if out and out[-1] in VALUE_OPTIONS and token[:1] == "-" and token[1:2].isdigit():
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


VALUE_OPTIONS = {"--size", "--frames", "--jobs", "--repeats", "--fail-under"}


def main(argv: list[str] | None = None) -> int:
    """Run one ``cs451`` command line; returns its exit status (0, 1, 2 or 3: see the module's docstring)."""
    argv = _joined_values(list(sys.argv[1:] if argv is None else argv))
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:   # --help, --version, or a mistake argparse said in one line: its status
        return exit_.code if isinstance(exit_.code, int) else 2
    verbose, quiet = getattr(args, "verbose", False), getattr(args, "quiet", False)
    if verbose and quiet:   # one on each side of the subcommand: argparse's own check sees only one side
        print("cs451: error: argument -q/--quiet: not allowed with argument -v/--verbose (see cs451 --help)",
              file=sys.stderr)
        return 2
    from .progress import set_quiet, set_verbose
    set_verbose(verbose)
    set_quiet(quiet)
    try:
        return args.func(args)
    except KitError as err:   # it may quote a submission (its file names): made printable
        from .grading.untrusted import printable
        print(printable(f"cs451: error: {err}"), file=sys.stderr)
        return 2
    except MemoryError:
        print("cs451: error: out of memory (the job's estimate missed it: please report the command)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cs451: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `cs451 scenes | head`: the reader left; say nothing more
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0
    except Exception as err:   # a bug in the kit, never the user's input: one line, the traceback on request
        if os.environ.get("CS451_TRACEBACK"):
            raise
        said = environment_error(err)
        if said:               # a path of the user's (missing, in the way, not writable; a full disk): theirs to fix
            from .grading.untrusted import printable
            print(printable(f"cs451: error: {said}", lines=False), file=sys.stderr)
            return 2
        where = traceback.extract_tb(err.__traceback__)[-1]
        print(f"cs451: internal error: {type(err).__name__}: {err} (at {Path(where.filename).name}:{where.lineno}; "
              f"a bug in the kit: please report it, with CS451_TRACEBACK=1 for the whole traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
