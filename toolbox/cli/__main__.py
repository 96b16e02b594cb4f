"""``python -m toolbox.cli``: the ``cct`` command without the console script."""

from . import run

if __name__ == "__main__":
    run()
