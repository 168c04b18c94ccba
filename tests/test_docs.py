"""The documentation site builds with warnings as errors and has its key pages; its generated parts track the code.

``mkdocs build --strict`` fails on any warning: a broken link or anchor, a page missing from the navigation, an
unresolved cross-reference in a docstring, a subcommand without its section on the CLI page, a failing example.
The site is built once per test session into a temporary directory.
"""

from __future__ import annotations

import html
import importlib.util
import logging
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import require_module

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
#: reference page -> the module it documents
REFERENCE_MODULES = {"motor": "model.motor", "catalog": "model.catalog", "sim": "sim", "control": "control",
                     "results": "sim.results", "experiments": "analysis.experiments", "compare": "analysis.compare",
                     "analytic": "model.analytic", "paper1": "analysis.paper1", "paper2": "analysis.paper2",
                     "identify": "analysis.identify", "sweep": "sweep", "store": "sweep.store",
                     "faults": "analysis.faults", "report": "report", "design": "model.design", "plots": "report.plots",
                     "units": "model.units", "errors": "errors", "cli": "cli"}


def _require_mkdocs() -> None:
    """Skip without the docs tools (``pip install ".[docs]"``); under CI (BLDCLAB_CI=1) fail instead."""
    require_module("mkdocs", "mkdocstrings_handlers", install='pip install ".[docs]"')


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    _require_mkdocs()
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(ROOT / "mkdocs.yml"), "--site-dir", str(out)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-6000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-6000:]
    return out


def _page(site: Path, path: str) -> str:
    f = site / path / "index.html" if not path.endswith(".html") else site / path
    assert f.is_file(), f"{f.relative_to(site)} was not built"
    return f.read_text(encoding="utf-8")


def _text(page: str) -> str:
    """The page's text: tags removed, entities decoded, whitespace collapsed."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", page)).split())


@pytest.mark.slow
def test_site_builds_strict_with_the_main_pages(site: Path) -> None:
    for path in ("index.html", "user-guide/install", "user-guide/cli", "user-guide/python", "motor-files",
                 "theory", "conventions", "plant", "theory-paper1", "theory-paper2", "sixstep", "sine", "identify",
                 "sweeps", "design", "developer", "developer/add-controller", "developer/add-back-emf",
                 "developer/testing", "gallery", "reference", "reference/bldclab"):
        _page(site, path)
    home = _text(_page(site, "index.html"))
    assert "pip install . && bldclab compare htm-48v" in home  # the README's quick start
    assert 'pip install ".[test]" && pytest' in home


@pytest.mark.slow
def test_api_reference_is_generated_from_the_docstrings(site: Path) -> None:
    for name, module in REFERENCE_MODULES.items():
        page = _page(site, f"reference/{name}")
        assert f'id="bldclab.{module}"' in page, f"reference/{name}: no section for bldclab.{module}"
    sim = _page(site, "reference/sim")
    for name in ("simulate", "Scenario", "Fault"):
        assert f'id="bldclab.sim.{name}"' in sim
    assert "Imposed mechanical speed (rad/s)" in _text(sim)  # a parameter description of Scenario
    control = _page(site, "reference/control")
    for name in ("control.base.Control", "control.openloop.SixStepVoltage", "control.openloop.OpenLoop",
                 "control.sixstep.SixStep", "control.sine.Sine", "control.lu.Lu"):
        assert f'id="bldclab.{name}"' in control
    motor = _page(site, "reference/motor")
    assert 'id="bldclab.model.motor.Drive.replace"' in motor and 'id="bldclab.model.emf.Fourier"' in motor
    assert 'id="bldclab.model.design.pi_gains"' in _page(site, "reference/design")


@pytest.mark.slow
def test_sphinx_roles_become_links_or_code(site: Path) -> None:
    for name in REFERENCE_MODULES:
        text = _text(_page(site, f"reference/{name}"))
        assert not re.search(r":(class|func|meth|mod|attr|data|exc):`", text), f"reference/{name}: a raw role"
    sim = _page(site, "reference/sim")
    # "Run the C closed loop: :func:`simulate` ... :class:`~bldclab.sim.results.SimResult`" in sim's module docstring
    assert 'href="../results/#bldclab.sim.results.SimResult"' in sim
    assert 'href="#bldclab.sim.simulate"' in sim


@pytest.mark.slow
def test_developer_guide_explains_how_to_add_a_controller_and_a_shape(site: Path) -> None:
    guide = _text(_page(site, "developer/add-controller"))
    assert "add a controller" in guide.lower()
    for name in ("bc_bind_mine.c", "PROVIDERS", "core/tests/test_mine.c", "params.h", "harness.c", "targets.c",
                 "src/bldclab/control/mine.py", "c_record", "with_delay", "test_controller_properties.py"):
        assert name in guide, name
    shape = _text(_page(site, "developer/add-back-emf"))
    assert "c_form" in shape and "BC_EMF_TABLE" in shape and "BC_EMF_FOURIER" in shape
    index = _text(_page(site, "developer"))
    for words in ("Prefix bc_", "malloc", "no globals, no I/O", "Frozen dataclasses", "numpydoc docstrings",
                  "PROVIDERS"):
        assert words in index, words


@pytest.mark.slow
def test_cli_page_shows_every_subcommand_with_its_current_help(site: Path) -> None:
    from bldclab.cli import COMMANDS

    text = _text(_page(site, "user-guide/cli"))
    assert "usage: bldclab [-h] [--version] COMMAND ..." in text
    for cmd in COMMANDS:
        assert f"usage: bldclab {cmd.name} [-h]" in text, cmd.name
        assert " ".join(cmd.help.split()) in text, cmd.name


@pytest.mark.slow
def test_every_example_has_a_gallery_page_with_its_figure_and_code(site: Path) -> None:
    assert EXAMPLES
    index = _page(site, "gallery")
    for script in EXAMPLES:
        page = _page(site, f"gallery/{script.stem}")
        figure = site / "gallery" / f"{script.stem}.png"
        assert figure.is_file() and figure.stat().st_size > 10_000, f"{figure.name}: no figure"
        assert f'src="../{script.stem}.png"' in page
        assert f'href="{script.stem}/"' in index
        code = _text(page)
        for line in script.read_text(encoding="utf-8").splitlines():
            if line.startswith("# configure") or line.startswith("# simulate"):
                assert line in code, f"{script.name}: {line!r} not on its page"


# ------------------------------------------------------------------------------------------------------------
# the generated parts fail when they drift from the code


def _hooks():
    _require_mkdocs()
    spec = importlib.util.spec_from_file_location("bldclab_docs_hooks", DOCS / "hooks.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses resolve their annotations through sys.modules
    spec.loader.exec_module(mod)
    return mod


def test_cli_page_check_fails_for_an_undocumented_or_unknown_subcommand(caplog: pytest.LogCaptureFixture) -> None:
    hooks = _hooks()
    page = (DOCS / "user-guide" / "cli.md").read_text(encoding="utf-8")
    with caplog.at_level(logging.WARNING):
        out = hooks._cli_page(page)
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert "<!-- bldclab-help" not in out
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        hooks._cli_page(page.replace("<!-- bldclab-help: sweep -->", "<!-- bldclab-help: swept -->"))
    messages = " ".join(r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING)
    assert "names no subcommand" in messages and "does not document the subcommand(s) sweep" in messages


def test_cli_help_is_what_the_command_prints() -> None:
    hooks = _hooks()
    env = {**os.environ, "COLUMNS": hooks.HELP_COLUMNS}
    proc = subprocess.run([sys.executable, "-m", "bldclab.cli", "identify", "--help"], env=env, capture_output=True,
                          text=True, check=True)
    assert hooks.cli_help(["identify"]) == proc.stdout.rstrip()


def test_a_failing_example_stops_the_build(tmp_path: Path) -> None:
    hooks = _hooks()
    bad = tmp_path / "broken.py"
    bad.write_text('"""Broken: raises."""\nraise SystemExit("no figure today")\n', encoding="utf-8")
    with pytest.raises(hooks.PluginError, match="failed"):
        hooks._run(bad)
    silent = tmp_path / "silent.py"
    silent.write_text('"""Silent: saves nothing."""\nprint("hello")\n', encoding="utf-8")
    with pytest.raises(hooks.PluginError, match="saved no figure"):
        hooks._run(silent)


# ------------------------------------------------------------------------------------------------------------
# the Python API tour runs


def test_python_tour_code_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every ```python block of the tour, in order, in one namespace: the page cannot drift from the API."""
    import matplotlib

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    text = (DOCS / "user-guide" / "python.md").read_text(encoding="utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
    assert len(blocks) >= 10
    namespace: dict[str, object] = {"__name__": "tour"}
    for j, block in enumerate(blocks):
        try:
            exec(compile(block, f"python.md block {j + 1}", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message names the block
            pytest.fail(f"python.md block {j + 1} failed: {exc!r}\n{block}")


def test_user_facing_text_cites_papers_by_reference_not_by_workspace_path() -> None:
    """Users have only the repository: README, docs, examples and the package never point outside it."""
    files = [ROOT / "README.md", *DOCS.rglob("*.md"), *EXAMPLES, *(ROOT / "src" / "bldclab").rglob("*.py")]
    offenders = [f"{f.relative_to(ROOT)}:{n}" for f in files
                 for n, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1)
                 if "shared/papers" in line or "/work/shared" in line or "../shared" in line]
    assert offenders == []


# ---------------------------------------------------------------------------------------------------------------
# a newcomer's path (issue 23, item 12): no site build needed

def test_readme_sends_a_newcomer_to_the_landing_page_first() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert readme.index("docs/index.md") < readme.index("docs/conventions.md")
    start = readme[readme.index("Start with:"):]
    assert start.splitlines()[2].startswith("- `docs/index.md`")


def test_the_landing_pages_quick_start_names_the_report() -> None:
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    quick = index[index.index("## Quick start"):index.index("## Where to go next")]
    assert "report.html" in quick


def test_the_cli_page_names_every_built_in_drive() -> None:
    from bldclab.model.catalog import names

    cli = (DOCS / "user-guide" / "cli.md").read_text(encoding="utf-8")
    intro = cli[:cli.index("Shared behaviour")]
    for name in names():
        assert f"`{name}`" in intro, name


def test_readme_synopsis_of_compare_and_effmap_lists_every_option() -> None:
    from bldclab.cli import build_parser

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    parser = build_parser(["compare", "effmap"])
    sub = next(a for a in parser._actions if hasattr(a, "choices") and isinstance(a.choices, dict))
    for command in ("compare", "effmap"):
        start = readme.index(f"bldclab {command} MOTOR")
        synopsis = readme[start:readme.index("\nbldclab ", start + 1)]
        for action in sub.choices[command]._actions:
            for option in action.option_strings:
                if option.startswith("--") and option != "--help" and (command == "compare" or option in (
                        "--chopping", "--verbose", "--generating", "--store", "--no-store", "--workers")):
                    assert option in synopsis, (command, option)
