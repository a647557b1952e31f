"""The second half of the docs' examples (docs/experiments.md, docs/sweeps.md, docs/deploy.md and the
model cards from models/p on; snake-py/tests/_doc_blocks.py's SECOND_HALF), run as
snake-py/tests/test_doc_examples.py runs the first, in a file of its own so that xdist runs the halves
on both cores."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _doc_blocks as docs  # noqa: E402


@pytest.mark.parametrize("page", docs.pages_with_examples(second_half=True))
def test_every_example_of_the_page_runs(page, tmp_path):
    docs.check_page(page, tmp_path)
