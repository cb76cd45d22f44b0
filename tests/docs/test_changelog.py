"""The changelog a user reads: Keep a Changelog's sections per version, and the env ids' versions in step with it."""

import re
from pathlib import Path

import gymnasium as gym

import box_toss_env

REPO = Path(__file__).resolve().parents[2]
CHANGELOG = REPO / "docs" / "changelog.md"
KINDS = {"Added", "Changed", "Deprecated", "Removed", "Fixed", "Security"}


def versions() -> dict[str, list[str]]:
    """Each version's heading (``[Unreleased]``, ``[0.1.0] - 2026-12-01``) and the headings of its sections."""
    found: dict[str, list[str]] = {}
    current = None
    for line in CHANGELOG.read_text().splitlines():
        if line.startswith("## "):
            current = line[3:].strip()
            found[current] = []
        elif line.startswith("### "):
            assert current is not None, f"{line!r} before any version"
            found[current].append(line[4:].strip())
    return found


def test_every_version_has_keep_a_changelog_sections():
    found = versions()
    assert found, "no version"
    for heading, sections in found.items():
        assert re.fullmatch(r"\[(Unreleased|\d+\.\d+\.\d+)\]( - \d{4}-\d{2}-\d{2})?", heading), heading
        assert sections and set(sections) <= KINDS, (heading, sections)
    assert list(found)[0] == "[Unreleased]" or "[Unreleased]" not in found  # the newest first


def test_the_package_version_is_the_changelogs_and_every_id_has_a_version_history():
    version = re.search(r'^version = "(.+)"$', (REPO / "pyproject.toml").read_text(), flags=re.MULTILINE)[1]
    assert box_toss_env.__version__ == version
    headings = re.findall(r"^## (\[[^\]]+\])", CHANGELOG.read_text(), flags=re.MULTILINE)
    assert len(headings) == len(set(headings))  # one section a version
    assert f"[{version}]" in headings or f"{version}" in CHANGELOG.read_text().split("## ", 2)[1]  # named there
    for env_id in (name for name in gym.registry if name.startswith("BoxToss")):
        spec = gym.spec(env_id)
        module, name = str(spec.entry_point).split(":")
        doc = getattr(__import__(module, fromlist=[name]), name).__doc__ or ""
        history = doc.split("## Version History", 1)[1] if "## Version History" in doc else ""
        assert f"* v{spec.version}:" in history, env_id  # the id's version is described in its env's docstring
