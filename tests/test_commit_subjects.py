"""Commit subjects are 72 characters or fewer, for every commit after the one where the rule began (older
subjects stay as they were: history is not rewritten). Skipped outside a git clone or where that commit is not in
the history (a shallow clone)."""

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
RULE_BASE = "0e389ec1dbcf1baa50abc81c173f7a69a148cdf2"
"""The last commit before the rule: every commit reachable from HEAD but not from it is checked."""
LIMIT = 72


def git(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["git", "-C", str(REPO), *args], capture_output=True, text=True)


def test_subjects_after_the_rule_began_are_72_characters_or_fewer():
    if shutil.which("git") is None or git("rev-parse", "--git-dir").returncode != 0:
        pytest.skip("not a git clone")
    if git("cat-file", "-e", f"{RULE_BASE}^{{commit}}").returncode != 0:
        pytest.skip(f"{RULE_BASE} is not in this clone's history (shallow?)")
    log = git("log", "--format=%h %s", f"{RULE_BASE}..HEAD")
    assert log.returncode == 0, log.stderr
    long = [line for line in log.stdout.splitlines() if len(line.split(" ", 1)[1]) > LIMIT]
    assert long == [], f"subjects over {LIMIT} characters (reword them before they land): {long}"


def test_the_commit_msg_hook_refuses_a_long_subject(tmp_path):
    hook = REPO / ".githooks" / "commit-msg"
    message = tmp_path / "message"
    message.write_text("A subject of a sensible length\n\n" + "a body line that may be long " * 10 + "\n")
    assert subprocess.run([str(hook), str(message)], capture_output=True).returncode == 0
    message.write_text("x" * 73 + "\n")
    refused = subprocess.run([str(hook), str(message)], capture_output=True, text=True)
    assert refused.returncode == 1 and "73 characters" in refused.stderr
