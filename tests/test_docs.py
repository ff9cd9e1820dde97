"""The documentation site builds with warnings as errors, and its generated reference is complete."""

import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]

pytest.importorskip("sphinx", reason="the docs extra: pip install -e '.[docs]'")


def _keys(spec: dict, path: str) -> list[str]:
    """Every key path of the schema below ``spec`` (objects in lists as ``key[].child``)."""
    out = [path] if path else []
    children = spec.get("properties")
    if not children and spec.get("items", {}).get("type") == "object":
        children = spec["items"].get("properties", {})
        path += "[]"
    for key, child in (children or {}).items():
        out += _keys(child, f"{path}.{key}" if path else key)
    return out


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-W",
            "--keep-going",
            "-q",
            "-b",
            "html",
            "-d",
            str(out / ".doctrees"),
            "docs",
            str(out),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, f"sphinx-build -W failed:\n{run.stderr[-4000:]}"
    return out


@pytest.mark.slow
def test_site_builds_without_warnings(site):
    for page in (
        "index",
        "getting_started",
        "performance",
        "reference/configuration",
        "reference/cli",
        "reference/api",
    ):
        assert (site / f"{page}.html").exists(), page


@pytest.mark.slow
def test_configuration_reference_lists_every_key(site):
    schema = yaml.safe_load((REPO / "config" / "schema.yaml").read_text())
    html = (site / "reference" / "configuration.html").read_text()
    text = re.sub(r"<[^>]+>", "", html)
    missing = [key for key in _keys(schema, "") if "." in key and key not in text]
    assert not missing, f"keys of config/schema.yaml missing from the configuration reference: {missing}"


@pytest.mark.slow
def test_cli_reference_lists_every_command(site):
    from piezobearing import cli

    parser = cli._parser()
    commands = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices
    text = re.sub(r"<[^>]+>", "", (site / "reference" / "cli.html").read_text())
    for name, sub in commands.items():
        assert f"piezobearing {name}" in text, name
        for action in sub._actions:
            for option in action.option_strings:
                assert option in text, f"{name} {option}"


_REMOTE = re.compile(r"<(?:script|link|img|iframe)\b[^>]*\b(?:src|href)=[\"'](?:https?:)?//", re.IGNORECASE)


@pytest.mark.slow
def test_site_loads_nothing_from_the_network(site):
    """No page loads a script, style sheet or image from another host: the site works offline and saved."""
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 20
    remote = [str(p.relative_to(site)) for p in pages if _REMOTE.search(p.read_text())]
    assert not remote, f"pages loading from the network: {remote}"


@pytest.mark.slow
def test_equations_are_mathml(site):
    """Every theory page's equations are MathML written at build time, with no LaTeX left for a script."""
    with_math = [p for p in sorted((REPO / "docs" / "theory").glob("*.md")) if "$" in p.read_text()]
    assert len(with_math) >= 4
    for source in with_math:
        page = site / "theory" / f"{source.stem}.html"
        html = page.read_text()
        assert "<math" in html, page.name
        text = re.sub(r"<[^>]+>", "", re.sub(r"<math.*?</math>", "", html, flags=re.DOTALL))
        assert not re.search(r"\\(frac|varepsilon|mathrm|text)\b", text), f"raw LaTeX in {page.name}"


@pytest.mark.slow
def test_site_shows_its_version_and_searches_offline(site):
    import piezobearing

    for page in ("index.html", "theory/calibration_circuit.html", "reference/api.html"):
        assert f"piezobearing {piezobearing.__version__}" in (site / page).read_text(), page
    search = (site / "search.html").read_text()
    assert (site / "searchindex.js").exists() and "searchindex.js" in search
    assert "kurtogram" in (site / "searchindex.js").read_text()
