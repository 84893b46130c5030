"""``python -m rplearn``: the same as the ``rplearn`` command."""

from rplearn.cli import main

if __name__ == "__main__":
    main()
