"""The `llfsm` command and `python -m llfsm`.

Kept apart from `llfsm.cli` so that nothing heavy is imported yet when it starts: a Ctrl-C
that lands while click, pydantic and the rest are still importing (the first tenth of a
second of every command) ends with status 130 and no output, exactly as one that lands later,
instead of a KeyboardInterrupt traceback.
"""

import sys


def main() -> None:
    try:
        from llfsm.cli import main as run_cli
    except KeyboardInterrupt:
        sys.exit(130)
    run_cli()


if __name__ == "__main__":
    main()
