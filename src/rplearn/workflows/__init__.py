"""Pipelines that the command line, the report and the tests share.

- :mod:`~rplearn.workflows.logs`: logs -> matched dataset; a swarm's links and headings.
- :mod:`~rplearn.workflows.learning`: fit, evaluate, predict, sweep on files.
- :mod:`~rplearn.workflows.report`: the report about one model (and the paper's Table I on request).
- :mod:`~rplearn.workflows.demo`: the paper's whole evaluation on a simulated campaign.
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
