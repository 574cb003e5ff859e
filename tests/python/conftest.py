"""Fixtures of the Python tests: the CLI (MULTICUE_CLI, set by ctest) and its demo scene."""

import os
import pathlib
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("MULTICUE_CLI")
    if not path or not os.path.exists(path):
        pytest.fail("MULTICUE_CLI must name the multicue executable (ctest sets it)")
    return path


@pytest.fixture(scope="session")
def demo(cli, tmp_path_factory):
    """`multicue demo --no-report`: the demo scene (scene.pcd) and the CLI's outputs."""
    out = tmp_path_factory.mktemp("demo")
    subprocess.run([cli, "demo", "--no-report", "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL)
    return pathlib.Path(out)
