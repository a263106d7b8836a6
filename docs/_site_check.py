"""Checks of the built HTML site that Sphinx does not make itself.

``conf.py`` runs :func:`check_site` when the build has finished and reports each problem as a
Sphinx warning, so that ``make docs`` (``sphinx-build -W``) fails on it:

* every script, stylesheet, image or frame a page loads is a file of the site, none comes from
  a CDN or another host, so the pages (their math included) render offline exactly as online;
* every page with math loads the bundled MathJax;
* no gallery example shows a leaked return value (``Text(...)``, ``<matplotlib.… object>``);
* no gallery card (title or tooltip) shows raw reST markup (backticks, ``**``).

Only the standard library is used, so the checks can be tested without Sphinx.
"""

from __future__ import annotations

import html
import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

__all__ = ["check_site", "page_problems"]

# (tag, attribute) pairs whose URL the browser fetches to render the page; <a href> and
# <link rel="next"> are navigation and may point anywhere
_LOADED = {("script", "src"), ("img", "src"), ("iframe", "src"), ("source", "src"),
           ("video", "src"), ("audio", "src"), ("embed", "src"), ("object", "data")}
_LOADED_LINK_RELS = {"stylesheet", "preload", "modulepreload", "icon", "shortcut", "manifest"}

# folders of the site that hold assets, not pages (the theme ships HTML templates in _static)
_NOT_PAGES = {"_static", "_images", "_downloads", "_sources"}

_LEAKED_REPR = re.compile(r"\bText\(\s*-?[\d.]|<matplotlib\.[\w.]+ object at|\bLine2D\(")
_RAW_MARKUP = re.compile(r"`|\*\*")


class _Resources(HTMLParser):
    """Collects the URLs a page loads, whether it has math, and the gallery's output
    blocks and card texts."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.loaded: list[str] = []
        self.has_math = False
        self.outputs: list[str] = []       # text of the sphinx-gallery output blocks
        self.cards: list[str] = []         # titles and tooltips of the gallery cards
        self._out_depth = 0                # > 0 inside a <div class="sphx-glr-script-out">
        self._title_depth = 0              # > 0 inside a card title
        self._buf: list[str] = []
        self._title_buf: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = {k: (v or "") for k, v in attrs}
        classes = a.get("class", "").split()
        for name, value in a.items():
            if (tag, name) in _LOADED and value:
                self.loaded.append(value)
        if tag == "link" and a.get("href") and \
                _LOADED_LINK_RELS & set(a.get("rel", "").lower().split()):
            self.loaded.append(a["href"])
        if "math" in classes and tag in ("span", "div"):
            self.has_math = True
        if "tooltip" in a:
            self.cards.append(a["tooltip"])
        if tag == "div":
            if self._out_depth:
                self._out_depth += 1
            elif "sphx-glr-script-out" in classes:
                self._out_depth = 1
                self._buf = []
            if self._title_depth:
                self._title_depth += 1
            elif "sphx-glr-thumbnail-title" in classes:
                self._title_depth = 1
                self._title_buf = []

    def handle_endtag(self, tag):
        if tag != "div":
            return
        if self._out_depth:
            self._out_depth -= 1
            if not self._out_depth:
                self.outputs.append("".join(self._buf))
        if self._title_depth:
            self._title_depth -= 1
            if not self._title_depth:
                self.cards.append("".join(self._title_buf))

    def handle_data(self, data):
        if self._out_depth:
            self._buf.append(data)
        if self._title_depth:
            self._title_buf.append(data)


def _is_external(url: str) -> bool:
    parts = urlsplit(url)
    return bool(parts.netloc) or parts.scheme not in ("", "data", "file")


def page_problems(page: Path, root: Path) -> list[str]:
    """The problems of one built HTML page (paths in the messages are relative to ``root``).

    Parameters
    ----------
    page : Path
        The HTML file.
    root : Path
        The site's output folder (``docs/_build/html``).

    Returns
    -------
    list of str
        One message per problem; empty when the page is fine.
    """
    parser = _Resources()
    parser.feed(page.read_text(encoding="utf-8", errors="replace"))
    name = page.relative_to(root).as_posix()
    problems = []
    local_mathjax = False
    for url in parser.loaded:
        if _is_external(url):
            problems.append(f"{name}: loads {url} from another host (the page must render "
                            "offline: bundle the file in the site)")
            continue
        parts = urlsplit(url)
        if parts.scheme == "data" or not parts.path:
            continue
        target = (page.parent / unquote(parts.path)).resolve()
        if not target.is_file():
            problems.append(f"{name}: loads {url}, which is not in the built site")
        elif "mathjax" in parts.path.lower():
            local_mathjax = True
    if parser.has_math and not local_mathjax:
        problems.append(f"{name}: has math but loads no bundled MathJax "
                        "(extension sphinx-mathjax-offline missing from conf.py?)")
    for text in parser.outputs:
        m = _LEAKED_REPR.search(text)
        if m:
            line = next(ln for ln in text.splitlines() if m.group(0) in ln)
            problems.append(f"{name}: the example's output shows a leaked return value "
                            f"{line.strip()!r} (end the block with a statement, not an "
                            "expression)")
    for text in parser.cards:
        text = html.unescape(text)
        if _RAW_MARKUP.search(text):
            problems.append(f"{name}: gallery card shows raw reST markup: {text[:80]!r}")
    return problems


def check_site(root: Path | str) -> list[str]:
    """The problems of every HTML page under ``root`` (see the module docstring).

    A file loaded from another host by many pages (a theme or extension setting) is reported
    once, with the number of pages.

    Parameters
    ----------
    root : Path or str
        The site's output folder (``docs/_build/html``).

    Returns
    -------
    list of str
        One message per problem, page by page; empty when the site is fine.
    """
    root = Path(root)
    problems: list[str] = []
    external: dict[str, list[str]] = {}       # message without the page name -> pages
    for page in sorted(root.rglob("*.html")):
        if any(part.startswith(".") or part in _NOT_PAGES for part in
               page.relative_to(root).parts[:-1]):
            continue
        for problem in page_problems(page, root):
            name, _, what = problem.partition(": ")
            if what.startswith("loads ") and "from another host" in what:
                if what not in external:
                    problems.append(problem)
                external.setdefault(what, []).append(name)
            else:
                problems.append(problem)
    for what, pages in external.items():
        if len(pages) > 1:
            i = problems.index(f"{pages[0]}: {what}")
            problems[i] = f"{pages[0]} and {len(pages) - 1} more pages: {what}"
    return problems
