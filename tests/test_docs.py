"""Every ```python block of README.md and of the documentation pages (docs/**/*.md) runs as
written: each file's blocks in order, in one namespace, in a fresh working directory in which the
repository's examples/ folder is available as examples/. Blocks in other languages (text, sh,
toml) are not run. The examples in the public docstrings run too (doctest)."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parent.parent
_SKIP = ("_build", "auto_examples", "generated")
FILES = [ROOT / "README.md"] + sorted(
    path
    for path in (ROOT / "docs").rglob("*.md")
    if not any(part in _SKIP for part in path.relative_to(ROOT / "docs").parts)
)
_FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|~{3,})\s*(?P<info>[^`\s]*)")


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, code) of each fenced block whose info string is ``python``."""
    blocks: list[tuple[int, str]] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        match = _FENCE.match(lines[i])
        if not match:
            i += 1
            continue
        fence, info = match["fence"], match["info"].strip("{}").lower()
        start = i + 1
        i = start
        while i < len(lines) and not lines[i].strip().startswith(fence):
            i += 1
        if info in ("python", "py"):
            blocks.append((start + 1, textwrap.dedent("\n".join(lines[start:i]))))
        i += 1
    return blocks


def test_the_block_parser_finds_python_blocks_only() -> None:
    text = "a\n```python\nx = 1\n```\n```sh\nls\n```\n  ```python\n  y = 2\n  ```\n"
    assert python_blocks(text) == [(3, "x = 1"), (9, "y = 2")]


def test_readme_and_docs_have_python_blocks() -> None:
    assert ROOT / "README.md" in WITH_CODE and ROOT / "docs" / "paper.md" in WITH_CODE
    assert sum(len(python_blocks(path.read_text())) for path in FILES) >= 10


WITH_CODE = [path for path in FILES if python_blocks(path.read_text())]


# Short documentation runs have not converged, and adparm says so: the ApproximationWarning a
# user sees when pasting them is expected here (every other warning is still an error).
_SHORT_RUNS_WARN = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")


@_SHORT_RUNS_WARN
@pytest.mark.parametrize("path", WITH_CODE, ids=[str(p.relative_to(ROOT)) for p in WITH_CODE])
def test_python_blocks_run(path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = python_blocks(path.read_text())
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    matplotlib.use("Agg")
    namespace: dict = {"__name__": "__main__"}
    for line, code in blocks:
        compiled = compile(code, f"{path.relative_to(ROOT)}:{line}", "exec")
        exec(compiled, namespace)  # noqa: S102 - running the documentation is the test
    import matplotlib.pyplot as plt

    plt.close("all")


@_SHORT_RUNS_WARN
@pytest.mark.parametrize(
    "module",
    [
        "adparm.bases",
        "adparm.config",
        "adparm.optimal",
        "adparm.physical",
        "adparm.simulation",
        "adparm.urdf",
    ],
)
def test_docstring_examples_run(module: str) -> None:
    import doctest
    import importlib

    failures, tried = doctest.testmod(importlib.import_module(module))
    assert tried > 0 and failures == 0


# --- code that readers save and run as files ---------------------------------------------------


def _run_script(path: Path, cwd: Path, timeout: float = 300.0) -> subprocess.CompletedProcess:
    """``python path`` in ``cwd``, as a reader runs a saved script: a fresh interpreter, the
    Agg backend, adparm from wherever this test imports it."""
    import os

    import adparm

    env = dict(os.environ, MPLBACKEND="Agg")
    package_root = str(Path(adparm.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [package_root, env.get("PYTHONPATH")]))
    return subprocess.run(
        [sys.executable, str(path)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def test_dask_block_runs_as_a_saved_script(tmp_path: Path) -> None:
    """The Dask example of many-runs.md, saved as a file and run with python: LocalCluster's
    worker processes import the file, so it needs its __main__ guard (without it every worker
    started a cluster of its own and the script failed with "Nanny failed to start")."""
    pytest.importorskip("dask.distributed")
    text = (ROOT / "docs" / "guide" / "many-runs.md").read_text()
    (code,) = [code for _, code in python_blocks(text) if "LocalCluster" in code]
    assert 'if __name__ == "__main__":' in code
    script = tmp_path / "sweep_dask.py"
    script.write_text(code + "\n")
    done = _run_script(script, tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "['finished' 'finished']" in done.stdout


GALLERY = sorted((ROOT / "docs" / "examples").glob("plot_*.py"))


@pytest.mark.parametrize("script", GALLERY, ids=[p.name for p in GALLERY])
def test_gallery_script_runs_downloaded_alone(script: Path, tmp_path: Path) -> None:
    """Each gallery script as a reader downloads it: alone in an empty folder, run with python
    (plot_urdf_arm.py once read ../../examples/planar_3link.toml, found from nowhere but the
    docs' own folder; it now loads adparm.example_path("planar_3link.toml"))."""
    copy = tmp_path / script.name
    shutil.copy(script, copy)
    done = _run_script(copy, tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "../" not in script.read_text()  # no path relative to the repository


def test_example_path_finds_the_installed_examples() -> None:
    import adparm

    path = adparm.example_path("planar_3link.toml")
    config = adparm.load_config(path)
    assert config.dof == 3 and Path(config.plant.urdf).is_file()
    shipped = sorted(p.relative_to(ROOT / "examples") for p in (ROOT / "examples").rglob("*.*"))
    assert sorted(p.relative_to(adparm.example_path()) for p in adparm.example_path().rglob("*.*"))
    for name in shipped:
        assert (
            adparm.example_path(str(name)).read_bytes() == (ROOT / "examples" / name).read_bytes()
        )
    package = Path(adparm.__file__).resolve().parent
    if not (package / "examples").is_dir():  # only a source tree may do without the copy
        assert package == ROOT / "python" / "adparm", f"{package} has no examples/"
    with pytest.raises(FileNotFoundError, match="no example 'nothing.toml'; there are: "):
        adparm.example_path("nothing.toml")
    with pytest.raises(FileNotFoundError):
        adparm.example_path("../README.md")


# --- what the set-up instructions claim ---------------------------------------------------------


def _extra(name: str) -> list[str]:
    from adparm.config import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    return [re.split(r"[\s<>=!\[;]", requirement, maxsplit=1)[0] for requirement in extras[name]]


def test_the_test_extra_has_the_docs_tools() -> None:
    """The README says `pip install ".[test]"` brings the documentation tools, and that the docs
    extra alone would build the extension again: the tools-only command it gives installs
    exactly the docs extra."""
    assert set(_extra("docs")) <= set(_extra("test"))
    for page in (ROOT / "README.md", ROOT / "docs" / "design.md"):
        text = page.read_text()
        (command,) = re.findall(r"^pip install (sphinx .*)$", text, flags=re.MULTILINE)
        assert sorted(command.split()) == sorted(_extra("docs")), page
        assert "builds the C++ extension again" in " ".join(text.split()), page


def test_documented_test_time_is_measured() -> None:
    for page in (ROOT / "README.md", ROOT / "docs" / "getting-started.md"):
        text = " ".join(page.read_text().split())
        assert "half a minute" not in text, page
        assert "minutes on a quiet 2-core machine" in text, page


# --- the landing figure ------------------------------------------------------------------------


def test_landing_figure_is_the_runs() -> None:
    """docs/_static/critic_weights.png (README and landing page) is drawn by
    docs/_ext/landing_figure.py from a run, again at every docs build; the texts stored in the
    committed PNG (title, labels, the clipped transient's numbers, legends) are a fresh run's.
    It once said "down to -88.6, up to 22.2" and "2 %" where the run gave -85.8, 23.6, 1 %."""
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        import landing_figure
    finally:
        sys.path.pop(0)
    matplotlib.use("Agg")
    stored = landing_figure.stored_texts()
    assert stored is not None, "redraw it: python docs/_ext/landing_figure.py"
    fresh = landing_figure.texts(landing_figure.draw())
    assert stored == fresh, "stale: redraw it with python docs/_ext/landing_figure.py"
    assert re.search(r"transient clipped \(down to -\d", fresh)
    assert "1 %" in fresh.splitlines()


# --- the site works offline and its anchors resolve --------------------------------------------

_EXT = ROOT / "docs" / "_ext"


def _tiny_site(tmp_path: Path, extensions: list[str]) -> tuple[int, Path, str]:
    """Builds a two-page Sphinx site (maths; objects of one module documented under two module
    names, as adparm.ExpressionBasis and adparm.bases.parse_term are) with ``extensions``;
    returns the exit status of ``sphinx-build -W``, the output folder and the log."""
    import os

    source, out = tmp_path / "src", tmp_path / "html"
    (source / "pkg").mkdir(parents=True)
    (source / "pkg" / "__init__.py").write_text("from .core import first\n")
    (source / "pkg" / "core.py").write_text(
        'def first():\n    """First."""\n\n\ndef second():\n    """Second."""\n'
    )
    (source / "conf.py").write_text(f"extensions = {extensions!r}\nexclude_patterns = ['pkg']\n")
    (source / "index.rst").write_text(
        "Site\n====\n\n.. toctree::\n\n   a\n   b\n\nMaths: :math:`x^2 + y^2`.\n"
    )
    (source / "a.rst").write_text("A\n=\n\n.. autofunction:: pkg.first\n")
    (source / "b.rst").write_text("B\n=\n\n.. autofunction:: pkg.core.second\n")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(source), str(_EXT), env.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html"]
        + [str(source), str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    return done.returncode, out, done.stdout + done.stderr


def _scan(out: Path) -> list[str]:
    sys.path.insert(0, str(_EXT))
    try:
        import html_checks
    finally:
        sys.path.pop(0)
    return html_checks.scan(out)


def test_site_serves_mathjax_and_its_anchors_resolve(tmp_path: Path) -> None:
    """Sphinx's defaults load MathJax from a CDN (maths shows as raw LaTeX offline) and
    viewcode's "[docs]" links of a module documented under two names point at missing ids (5 in
    _modules/adparm/bases.html): the docs' extensions serve MathJax from the site and give those
    objects the ids; html_checks then finds nothing, and the build passes with -W."""
    pytest.importorskip("sphinx")
    base = ["sphinx.ext.autodoc", "sphinx.ext.viewcode"]
    status, out, log = _tiny_site(tmp_path / "default", [*base, "sphinx.ext.mathjax"])
    assert status == 0, log
    problems = _scan(out)
    assert any("link to a missing anchor" in p and "#pkg.second" in p for p in problems)
    assert any("loads https://" in p and "mathjax" in p.lower() for p in problems)

    status, out, log = _tiny_site(tmp_path / "ours", [*base, "local_mathjax", "html_checks"])
    assert status == 0, log
    assert _scan(out) == []
    page = (out / "index.html").read_text()
    assert 'src="_static/mathjax/tex-chtml.js"' in page
    assert (out / "_static" / "mathjax" / "tex-chtml.js").stat().st_size > 100_000
    fonts = out / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2"
    assert len(list(fonts.glob("*.woff"))) > 10
    assert (out / "_static" / "mathjax" / "input" / "tex" / "extensions").is_dir()


def test_html_checks_fail_the_build(tmp_path: Path) -> None:
    """html_checks reports a broken anchor, a missing file and a remote script, as warnings
    that -W turns into a failed build."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "a.html").write_text(
        '<html><body><p id="here">x</p><a href="#here">ok</a><a href="b.html#gone">x</a>'
        '<a href="b.html#there">ok</a><script src="https://cdn.example/x.js"></script>'
        '<img src="_static/none.png"></body></html>'
    )
    (site / "b.html").write_text('<html><body><span id="there"></span></body></html>')
    problems = _scan(site)
    assert len(problems) == 3, problems
    assert "a.html: link to a missing anchor: b.html#gone" in problems
    assert any("loads https://cdn.example/x.js from the network" in p for p in problems)
    assert any("loads a missing file: _static/none.png" in p for p in problems)
