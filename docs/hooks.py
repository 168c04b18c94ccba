"""MkDocs hooks (``hooks:`` in mkdocs.yml): the parts of the site generated from the code at build time.

- **Command line.** ``<!-- bldclab-help: CMD -->`` in a page becomes the output of ``bldclab CMD --help``
  (``<!-- bldclab-help -->``: ``bldclab --help``), at a fixed width of 100 columns. Every subcommand of
  :data:`bldclab.cli.COMMANDS` must have its marker on ``user-guide/cli.md`` and every marker must name a
  subcommand: otherwise the build warns, and ``--strict`` fails. A new subcommand therefore needs its section.
- **Gallery.** Every ``examples/*.py`` is run (in parallel, with a figure path argument, in a temporary
  directory) and becomes a page ``gallery/<name>.md``: its docstring (title and text), the figure it saved, what it
  printed, and its source, read from the file. The pages are added to the navigation (labelled with the title up
  to its first colon) under the entry whose page is ``gallery/index.md``, where ``<!-- gallery-list -->`` becomes a
  list of them. An example that fails or saves no
  figure stops the build.
"""

from __future__ import annotations

import ast
import concurrent.futures
import contextlib
import io
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.plugins import get_plugin_logger
from mkdocs.structure.files import File, Files

log = get_plugin_logger("bldclab")

CLI_PAGE = "user-guide/cli.md"
GALLERY_DIR = "gallery"
GALLERY_INDEX = f"{GALLERY_DIR}/index.md"
HELP_MARK = re.compile(r"<!--\s*bldclab-help(?::\s*([\w-]+))?\s*-->")
GALLERY_MARK = "<!-- gallery-list -->"
HELP_COLUMNS = "100"
EXAMPLE_TIMEOUT = 300  # s per example


@dataclass(frozen=True)
class Example:
    """One gallery example after its run."""

    stem: str
    path: Path
    title: str
    text: str
    source: str
    stdout: str
    figure: bytes
    seconds: float


_cache: dict[tuple[str, str], Example] = {}  # (path, source) -> run, so `mkdocs serve` reruns only changed files


def _root(config: Any) -> Path:
    return Path(config.config_file_path).resolve().parent


def _examples(config: Any) -> list[Path]:
    return sorted((_root(config) / "examples").glob("*.py"))


def _docstring(path: Path) -> tuple[str, str]:
    """Return the title (first docstring line) and the rest of an example's docstring."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))
    if not doc:
        raise PluginError(f"{path.name}: an example needs a docstring (title line, then what it shows)")
    title, _, text = doc.partition("\n")
    return title.strip().rstrip("."), text.strip()


def _nav_label(path: Path) -> str:
    """Return the navigation label of an example: its title up to the first colon."""
    return _docstring(path)[0].split(":", 1)[0]


# ------------------------------------------------------------------------------------------------------------
# navigation


def on_config(config: Any) -> Any:
    """Put one navigation entry per example under the gallery's section."""
    pages = [{_nav_label(p): f"{GALLERY_DIR}/{p.stem}.md"} for p in _examples(config)]

    def expand(items: list[Any]) -> bool:
        for j, item in enumerate(items):
            if not isinstance(item, dict):
                continue
            (name, value), = item.items()
            if value == GALLERY_INDEX:
                items[j] = {name: [GALLERY_INDEX, *pages]}
                return True
            if isinstance(value, list) and expand(value):
                return True
        return False

    if not expand(config["nav"] or []):
        raise PluginError(f"mkdocs.yml: the navigation needs an entry whose page is {GALLERY_INDEX}")
    return config


# ------------------------------------------------------------------------------------------------------------
# gallery


def _run(path: Path) -> Example:
    """Run one example with a figure path in a fresh temporary directory (as tests/test_examples.py does)."""
    source = path.read_text(encoding="utf-8")
    key = (str(path), source)
    if key in _cache:
        return _cache[key]
    title, text = _docstring(path)
    with tempfile.TemporaryDirectory(prefix="bldclab-docs-") as tmp:
        figure = Path(tmp) / f"{path.stem}.png"
        start = time.perf_counter()
        env = {**os.environ, "MPLBACKEND": "Agg"}
        try:
            proc = subprocess.run([sys.executable, str(path), str(figure)], cwd=tmp, env=env, capture_output=True,
                                  text=True, timeout=EXAMPLE_TIMEOUT)
        except subprocess.TimeoutExpired:
            raise PluginError(f"examples/{path.name} did not finish within {EXAMPLE_TIMEOUT} s") from None
        seconds = time.perf_counter() - start
        if proc.returncode != 0:
            raise PluginError(f"examples/{path.name} failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
        if not figure.is_file():
            raise PluginError(f"examples/{path.name} saved no figure to the path given as its argument")
        ex = Example(path.stem, path, title, text, source, proc.stdout, figure.read_bytes(), seconds)
    _cache[key] = ex
    return ex


def _page(ex: Example) -> str:
    output = ex.stdout.rstrip() or "(nothing printed)"
    return "\n".join([
        f"# {ex.title}",
        "",
        ex.text,
        "",
        f"![Figure saved by examples/{ex.path.name}]({ex.stem}.png)",
        "",
        "## Output",
        "",
        "```text",
        output,
        "```",
        "",
        f"Run it with `python examples/{ex.path.name} figure.png` (the figure is written only when a path is given; "
        f"{ex.seconds:.1f} s when this page was built).",
        "",
        "## Code",
        "",
        f'```python title="examples/{ex.path.name}"',
        ex.source.rstrip(),
        "```",
        "",
    ])


def on_files(files: Files, config: Any) -> Files:
    """Run every example and add its gallery page and figure to the site."""
    paths = _examples(config)
    if not paths:
        raise PluginError("examples/ holds no example")
    start = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, os.cpu_count() or 1)) as pool:
        examples = list(pool.map(_run, paths))
    log.info("ran %d examples in %.1f s", len(examples), time.perf_counter() - start)
    for ex in examples:
        for name, content in ((f"{ex.stem}.md", _page(ex)), (f"{ex.stem}.png", ex.figure)):
            uri = f"{GALLERY_DIR}/{name}"
            if files.get_file_from_path(uri) is not None:
                raise PluginError(f"docs/{uri} exists: gallery pages are generated from examples/{ex.path.name}")
            files.append(File.generated(config, uri, content=content))
    return files


def _gallery_list(config: Any) -> str:
    """One section per example: its title as a link and its figure as a thumbnail linking to its page."""
    lines = []
    for path in _examples(config):
        title, _ = _docstring(path)
        lines += [f"### [{title}]({path.stem}.md)", "",
                  f'[![{title}]({path.stem}.png){{ width="560" }}]({path.stem}.md)', ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------------------
# command line


def cli_help(args: list[str]) -> str:
    """Return what ``bldclab ARGS --help`` prints at a width of 100 columns."""
    from bldclab.cli import main

    buf = io.StringIO()
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = HELP_COLUMNS
    try:
        with contextlib.redirect_stdout(buf):
            code = main([*args, "--help"])
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    if code != 0:
        raise PluginError(f"bldclab {' '.join(args)} --help exited with {code}")
    return buf.getvalue().rstrip()


def _cli_page(markdown: str) -> str:
    from bldclab.cli import COMMANDS

    commands = [c.name for c in COMMANDS]
    seen: list[str] = []

    def block(match: re.Match[str]) -> str:
        name = match.group(1)
        if name is not None:
            if name not in commands:
                log.warning("%s: <!-- bldclab-help: %s --> names no subcommand (bldclab.cli.COMMANDS: %s)",
                            CLI_PAGE, name, ", ".join(commands))
                return ""
            seen.append(name)
        return "```text\n" + cli_help([name] if name else []) + "\n```"

    out = HELP_MARK.sub(block, markdown)
    missing = [c for c in commands if c not in seen]
    if missing:
        log.warning("%s does not document the subcommand(s) %s: add a section with <!-- bldclab-help: NAME -->",
                    CLI_PAGE, ", ".join(missing))
    return out


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    """Fill in the generated parts of the CLI page and the gallery index."""
    uri = page.file.src_uri
    if uri == CLI_PAGE:
        return _cli_page(markdown)
    if uri == GALLERY_INDEX:
        if GALLERY_MARK not in markdown:
            log.warning("%s: needs the marker %s", uri, GALLERY_MARK)
        return markdown.replace(GALLERY_MARK, _gallery_list(config))
    return markdown
