"""``python -m rplearn.cli``: the same as the ``rplearn`` script."""

from rplearn.cli import main

main()
