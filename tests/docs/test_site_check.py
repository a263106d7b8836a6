"""The checks ``make docs`` runs on the built site (``docs/_site_check.py``) and the settings of
``docs/conf.py`` they rely on."""

import ast
import importlib.util
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"

_spec = importlib.util.spec_from_file_location("_site_check", DOCS / "_site_check.py")
site_check = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(site_check)

HEAD = '<html><head>{}</head><body>{}</body></html>'


def _site(tmp_path, head="", body="", static=("_static/doctools.js",)):
    for name in static:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("//", encoding="utf-8")
    (tmp_path / "page.html").write_text(HEAD.format(head, body), encoding="utf-8")
    return tmp_path


def test_local_assets_pass(tmp_path):
    root = _site(tmp_path, '<script src="_static/doctools.js?v=1"></script>'
                           '<link rel="stylesheet" href="_static/doctools.js">'
                           '<a href="https://example.org/">a link is not a load</a>')
    assert site_check.check_site(root) == []


@pytest.mark.parametrize("tag", [
    '<script defer src="https://cdn.jsdelivr.net/npm/mathjax@4/tex-mml-chtml.js"></script>',
    '<script src="//code.jquery.com/jquery.js"></script>',
    '<link href="https://cdn.example.org/x.css" rel="stylesheet">',
    '<img src="http://example.org/logo.png">',
])
def test_asset_from_another_host_fails(tmp_path, tag):
    problems = site_check.check_site(_site(tmp_path, tag))
    assert len(problems) == 1 and "another host" in problems[0], problems


def test_missing_local_asset_fails(tmp_path):
    problems = site_check.check_site(_site(tmp_path, '<script src="_static/gone.js"></script>'))
    assert len(problems) == 1 and "not in the built site" in problems[0]


def test_math_needs_the_bundled_mathjax(tmp_path):
    math = '<span class="math notranslate nohighlight">\\(V_f\\)</span>'
    problems = site_check.check_site(_site(tmp_path, body=math))
    assert len(problems) == 1 and "MathJax" in problems[0]
    root = _site(tmp_path, '<script defer src="_static/mathjax/tex-chtml.js"></script>', math,
                 static=("_static/mathjax/tex-chtml.js",))
    assert site_check.check_site(root) == []


def test_leaked_return_value_in_gallery_output_fails(tmp_path):
    out = ('<div class="sphx-glr-script-out highlight-none"><div class="highlight"><pre>'
           "flutter: V_f = 2.1704\nText(0.5, 36.8, &#39;speed index&#39;)\n</pre></div></div>")
    problems = site_check.check_site(_site(tmp_path, body=out))
    assert len(problems) == 1 and "Text(0.5, 36.8" in problems[0]
    clean = out.replace("Text(0.5, 36.8, &#39;speed index&#39;)", "Text(s) printed on purpose")
    assert site_check.check_site(_site(tmp_path, body=clean)) == []


def test_raw_markup_in_gallery_card_fails(tmp_path):
    card = ('<div class="sphx-glr-thumbcontainer" tooltip="{}"><div class="sphx-glr-thumbnail-title">'
            '{}</div></div>')
    bad = card.format("what make demo (``casflutter run``) does", "A sweep (``casflutter sweep``)")
    problems = site_check.check_site(_site(tmp_path, body=bad))
    assert len(problems) == 2 and all("raw reST markup" in p for p in problems)
    good = card.format("what make demo (casflutter run) does", "A sweep (casflutter sweep)")
    assert site_check.check_site(_site(tmp_path, body=good)) == []


def test_theme_templates_in_static_are_not_pages(tmp_path):
    root = _site(tmp_path)
    (root / "_static" / "macros.html").write_text(
        "<script src=\"{{ pathto('_static/x.js', 1) }}\"></script>", encoding="utf-8")
    assert site_check.check_site(root) == []


def _conf_value(name):
    for node in ast.parse((DOCS / "conf.py").read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == name
                                                for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError(f"docs/conf.py sets no {name}")


def test_conf_renders_math_offline_and_prose_as_prose():
    extensions = _conf_value("extensions")
    assert "sphinx.ext.mathjax" in extensions and "sphinx-mathjax-offline" in extensions
    assert _conf_value("default_role") == "autolink"      # not "code": no chips for prose


def test_a_host_loaded_by_many_pages_is_reported_once(tmp_path):
    root = _site(tmp_path, '<script src="https://cdn.example.org/x.js"></script>')
    for k in range(3):
        (root / f"p{k}.html").write_text((root / "page.html").read_text(), encoding="utf-8")
    problems = site_check.check_site(root)
    assert problems == ["p0.html and 3 more pages: loads https://cdn.example.org/x.js from "
                        "another host (the page must render offline: bundle the file in the site)"]
