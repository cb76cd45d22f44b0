"""The documentation site as a reader gets it, built by mkdocs: the API reference shows the public API only (no
special members, no docstring inherited from Python's built-ins), and no user page carries a paragraph over
MAX_WORDS words. User pages are every page of mkdocs.yml's nav outside the sections of methodology, the API
reference and the changelog, where a benchmark's method is written out in full."""

import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[2]
MAX_WORDS = 150
NOT_USER_PAGES = ("Methodology", "API reference", "Changelog")
BUILTIN_DOCSTRINGS = (
    "dict() -> new empty dictionary",
    "bool(x) -> bool",
    "list() -> new empty list",
    "str(object='') -> str",
    "Return self==value",
    "Initialize self.  See help(type(self))",
    "Create and return a new object.",
    "Implement delattr(self, name)",
    "list of weak references to the object",
)
DUNDER = re.compile(r"\b__[a-z][a-z0-9_]*__\b")


def nav_pages(nav, section: str = "") -> list[tuple[str, str]]:
    """(top-level section, page path) of every page in mkdocs.yml's nav."""
    pages = []
    for entry in nav:
        if isinstance(entry, str):
            pages.append((section, entry))
            continue
        ((title, value),) = entry.items()
        if isinstance(value, list):
            pages += nav_pages(value, section or title)
        else:
            pages.append((section or title, value))
    return pages


NAV = nav_pages(yaml.safe_load((REPO / "mkdocs.yml").read_text())["nav"])
USER_PAGES = [page for section, page in NAV if section not in NOT_USER_PAGES]


def built_page(site: Path, page: str) -> Path:
    stem = page.rsplit(".", 1)[0]
    folder = stem[: -len("index")] if stem == "index" or stem.endswith("/index") else stem + "/"
    return site / folder / "index.html"


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    pytest.importorskip("mkdocs")
    out = tmp_path_factory.mktemp("site")
    build = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        env={"NO_MKDOCS_2_WARNING": "1", **dict(__import__("os").environ)},
    )
    assert build.returncode == 0, build.stderr[-4000:]
    return out


class Blocks(HTMLParser):
    """The text of each paragraph (``<p>``) and list item (``<li>``, without its nested blocks) of a page's
    article, and the ids and headings of its API entries."""

    BLOCKS = ("p", "li")

    def __init__(self):
        super().__init__()
        self.blocks: list[str] = []
        self.ids: list[str] = []
        self.headings: list[str] = []
        self.stack: list[list[str]] = []
        self.heading: list[str] | None = None
        self.in_article = 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "article":
            self.in_article += 1
        if not self.in_article:
            return
        if attrs.get("id"):
            self.ids.append(attrs["id"])
        if tag in self.BLOCKS:
            self.stack.append([])
        if tag in ("h1", "h2", "h3", "h4", "h5", "h6"):
            self.heading = []

    def handle_endtag(self, tag):
        if tag == "article":
            self.in_article -= 1
        if tag in self.BLOCKS and self.stack:
            self.blocks.append(" ".join("".join(self.stack.pop()).split()))
        if tag.startswith("h") and tag[1:].isdigit() and self.heading is not None:
            self.headings.append("".join(self.heading))
            self.heading = None

    def handle_data(self, data):
        if self.stack:
            self.stack[-1].append(data)
        if self.heading is not None:
            self.heading.append(data)


def read_page(path: Path) -> Blocks:
    parser = Blocks()
    parser.feed(path.read_text())
    return parser


def test_every_nav_page_is_built(site):
    assert [page for _, page in NAV if not built_page(site, page).exists()] == []


@pytest.mark.parametrize("page", USER_PAGES)
def test_no_user_page_carries_a_paragraph_over_the_limit(site, page):
    long = [block for block in read_page(built_page(site, page)).blocks if len(block.split()) > MAX_WORDS]
    assert long == [], f"{page}: {[f'{len(b.split())} words: {b[:120]}...' for b in long]}"


def test_no_page_documents_a_special_member_or_a_builtin_docstring(site):
    found = []
    for path in sorted(site.rglob("index.html")):
        page = read_page(path)
        text = path.read_text()
        found += [f"{path.relative_to(site)}: id {i}" for i in page.ids if DUNDER.search(i)]
        found += [f"{path.relative_to(site)}: heading {h}" for h in page.headings if DUNDER.search(h)]
        found += [f"{path.relative_to(site)}: {doc!r}" for doc in BUILTIN_DOCSTRINGS if doc in text]
    assert found == []


def test_the_site_keeps_the_limit_in_its_own_test_pages_list():
    """The split this test makes: the methodology pages exist, and every user page is in the nav once."""
    sections = {section for section, _ in NAV}
    assert "Methodology" in sections
    assert len(USER_PAGES) == len(set(USER_PAGES))
