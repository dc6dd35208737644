"""The container recipes run the README's own two commands (Docker is not runnable on every machine that
runs these tests, so what is checked here is that the recipes and the README cannot drift apart; CI runs
the same two commands from a fresh clone)."""
from __future__ import annotations

import json
import re
import shlex

from cs451 import KIT_ROOT


def readme_commands() -> list[str]:
    block = re.search(r"## Quick start.*?```sh\n(.*?)```", (KIT_ROOT / "README.md").read_text(), re.S).group(1)
    return [line.split("#")[0].strip() for line in block.strip().splitlines()]


def test_the_dockerfile_sets_up_and_tests_as_the_readme_says():
    text = (KIT_ROOT / "Dockerfile").read_text()
    setup, test = readme_commands()
    assert f"RUN {setup}" in text
    cmd = json.loads(re.search(r"^CMD (\[.*\])$", text, re.M).group(1))
    assert cmd == shlex.split(test)
    # The image starts where the fresh-Debian seat does (tests/test_seat_debian.py: bookworm with python3) and
    # leaves every other package to setup.sh, so a package setup.sh forgets fails there too instead of hiding here.
    assert re.search(r"^FROM debian:bookworm(-slim)?$", text, re.M)
    apt = re.search(r"apt-get install[^\n]*?--no-install-recommends ([\w .-]+?)\s*\\?\n", text).group(1).split()
    assert set(apt) <= {"python3", "python3-venv", "ca-certificates"}, apt


def test_the_devcontainer_builds_the_dockerfile_and_runs_the_setup():
    config = json.loads((KIT_ROOT / ".devcontainer" / "devcontainer.json").read_text())
    assert config["build"]["dockerfile"] == "../Dockerfile"
    assert config["postCreateCommand"] == readme_commands()[0]


def test_the_dockerignore_keeps_the_checkout_s_litter_out():
    ignored = (KIT_ROOT / ".dockerignore").read_text().split()
    assert {".venv/", ".git/", ".cs451-cache/"} <= set(ignored)
