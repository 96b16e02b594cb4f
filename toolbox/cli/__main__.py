"""``python -m toolbox.cli``: the ``cct`` command without the console script."""

from ._main import main

if __name__ == "__main__":
    main(prog_name="cct")
