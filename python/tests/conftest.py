"""Shared fixtures: the CLI binary the Python results are compared with."""

import os

import pytest


@pytest.fixture(scope="session")
def partscene_bin():
    """`PARTSCENE_BIN`, a built `partscene` binary; the comparisons fail under CI=true without it."""
    path = os.environ.get("PARTSCENE_BIN")
    if not path:
        if os.environ.get("CI") == "true":
            pytest.fail("PARTSCENE_BIN is not set: the CLI comparison cannot run")
        pytest.skip("PARTSCENE_BIN is not set (a built partscene binary to compare with)")
    return path
