"""The report scripts' way out: a missing or unreadable ledger or CSV is one line and exit code 2."""
import pathlib
import sys


def run(main) -> None:
    """``sys.exit(main(argv))``, a file error as one line naming the script."""
    try:
        sys.exit(main(sys.argv[1:]))
    except (FileNotFoundError, OSError, ValueError) as e:
        print(f"{pathlib.Path(sys.argv[0]).name}: {e}", file=sys.stderr)
        sys.exit(2)
