"""The documentation's snippets, run as a reader would run them.

Pages: ``docs/getting-started.md``, ``docs/guides/*.md`` and ``docs/robots/*.md``, one
test each. Each page's blocks run in order, in one Python namespace, in a fresh
temporary working folder:

- a ```` ```python ```` block is executed;
- a ```` ```toml ```` block whose first line is ``# file: NAME.toml`` is written to the
  folder as ``NAME.toml`` (for the blocks after it);
- a ```` ```console ```` block's lines that start with ``$ clik `` (or
  ``$ .venv/bin/clik ``) run through :func:`clik.cli.main` and must exit 0, unless the
  line ends with ``# exits N``; its other lines (output, other commands) are not run;
- other blocks are not run, nor a block preceded by ``<!-- skip -->`` (or
  ``<!-- skip: the reason -->``) on its own line;
- a ```` ```text ```` block preceded by ``<!-- output -->`` on its own line is what the
  block before it printed (stdout), line by line; only a wall time (``wall time 0.006
  s``) may differ.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
SKIP = "<!-- skip -->"
OUTPUT = "<!-- output -->"
WALL_TIME = re.compile(r"wall time [0-9.e+-]+ s")
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[^\n]*$")
FILE_LINE = re.compile(r"^#\s*file:\s*(?P<name>[\w.-]+\.toml)\s*$")
EXITS = re.compile(r"#\s*exits\s+(?P<code>\d+)\s*$")
COMMAND_PREFIXES = ("$ clik ", "$ .venv/bin/clik ")


def pages() -> list[Path]:
    """The pages whose snippets run, relative to ``docs/``."""
    found = [DOCS / "getting-started.md"]
    found += sorted((DOCS / "guides").glob("*.md")) + sorted((DOCS / "robots").glob("*.md"))
    return [p.relative_to(DOCS) for p in found if p.exists()]


@dataclass(frozen=True)
class Block:
    """One fenced block of a page."""

    lang: str
    text: str
    line: int  # 1-based line of the opening fence
    mark: str  # the last non-blank line before it (SKIP, OUTPUT or any text)

    @property
    def skip(self) -> bool:
        """Whether the block is marked not to run."""
        return self.mark == SKIP or (
            self.mark.startswith("<!-- skip:") and self.mark.endswith("-->")
        )


def blocks(markdown: str) -> list[Block]:
    """The fenced blocks of a page, in order (indented fences too, their indent removed)."""
    lines = markdown.splitlines()
    found: list[Block] = []
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        indent = opening["indent"]
        previous = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
        body: list[str] = []
        j = i + 1
        while j < len(lines) and lines[j].strip() != "```":
            body.append(lines[j][len(indent) :] if lines[j].startswith(indent) else lines[j])
            j += 1
        if j == len(lines):
            raise AssertionError(f"line {i + 1}: a ``` block that is never closed")
        found.append(Block(opening["lang"], "\n".join(body) + "\n", i + 1, previous))
        i = j + 1
    return found


def commands(text: str) -> list[tuple[list[str], int]]:
    """A console block's clik commands: (arguments after ``clik``, expected exit code)."""
    found = []
    for line in text.splitlines():
        if not line.startswith(COMMAND_PREFIXES):
            continue
        exits = EXITS.search(line)
        words = shlex.split(line[2:], comments=True)
        found.append((words[1:], int(exits["code"]) if exits else 0))
    return found


def comparable(output: str) -> list[str]:
    """Printed lines as a page shows them: trailing spaces and wall times ignored."""
    return [WALL_TIME.sub("wall time ... s", line.rstrip()) for line in output.strip().splitlines()]


def run_page(page: Path, folder: Path, capsys: pytest.CaptureFixture[str]) -> int:
    """Run a page's blocks in ``folder`` (the working folder); returns the blocks run."""
    from clik.cli import main

    namespace: dict[str, object] = {"__name__": "__docs__"}
    ran = 0
    printed = ""  # what the last block that ran printed
    for block in blocks((DOCS / page).read_text(encoding="utf-8")):
        where = f"docs/{page}:{block.line}"
        if block.skip:
            continue
        if block.lang == "text" and block.mark == OUTPUT:
            assert comparable(block.text) == comparable(printed), f"{where}: not what is printed"
        elif block.lang == "python":
            capsys.readouterr()
            exec(compile(block.text, where, "exec"), namespace)
            printed = capsys.readouterr().out
            ran += 1
        elif block.lang == "toml":
            first = block.text.splitlines()[0] if block.text.strip() else ""
            named = FILE_LINE.match(first.strip())
            if named is not None:
                (folder / named["name"]).write_text(block.text, encoding="utf-8")
                ran += 1
        elif block.lang == "console":
            capsys.readouterr()
            printed = ""
            for argv, expected in commands(block.text):
                code = main(argv)
                captured = capsys.readouterr()
                err, printed = captured.err, printed + captured.out
                assert code == expected, (
                    f"{where}: `clik {shlex.join(argv)}` exited {code}, expected {expected}\n{err}"
                )
                ran += 1
    return ran


@pytest.mark.parametrize("page", pages(), ids=str)
def test_page_snippets_run(
    page: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    run_page(page, tmp_path, capsys)


def test_the_getting_started_page_is_collected_and_runs_something(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert Path("getting-started.md") in pages()
    monkeypatch.chdir(tmp_path)
    assert run_page(Path("getting-started.md"), tmp_path, capsys) >= 4


SAMPLE = """\
Text.

```python
x = 1
```

<!-- skip -->
```python
raise SystemExit
```

<!-- skip: needs your own robot -->
```python
raise SystemExit
```

- a list item:

    ```toml
    # file: a.toml
    key = 1
    ```

```console
$ clik robots
robot names...
$ make demo
$ .venv/bin/clik solve a.toml --out out  # exits 3
```
"""


def test_blocks_reads_languages_skips_and_indents() -> None:
    found = blocks(SAMPLE)
    assert [(b.lang, b.skip) for b in found] == [
        ("python", False),
        ("python", True),
        ("python", True),
        ("toml", False),
        ("console", False),
    ]
    assert found[3].text == "# file: a.toml\nkey = 1\n"
    assert found[0].line == 3


def test_commands_takes_clik_lines_and_their_exit_codes() -> None:
    console = blocks(SAMPLE)[4]
    assert commands(console.text) == [
        (["robots"], 0),
        (["solve", "a.toml", "--out", "out"], 3),
    ]


def test_an_output_block_must_match_what_was_printed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    page = tmp_path / "page.md"
    body = (
        "```python\nprint('wall time 0.5 s, 2 steps')\n```\n\n<!-- output -->\n```text\n{}\n```\n"
    )
    monkeypatch.setattr(f"{__name__}.DOCS", tmp_path)
    monkeypatch.chdir(tmp_path)
    page.write_text(body.format("wall time 0.001 s, 2 steps"), encoding="utf-8")
    assert run_page(Path("page.md"), tmp_path, capsys) == 1
    page.write_text(body.format("wall time 0.001 s, 3 steps"), encoding="utf-8")
    with pytest.raises(AssertionError, match=r"docs/page\.md:6: not what is printed"):
        run_page(Path("page.md"), tmp_path, capsys)


def test_an_unclosed_block_is_an_error() -> None:
    with pytest.raises(AssertionError, match="never closed"):
        blocks("```python\nx = 1\n")


def test_a_failing_command_names_the_page_and_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    page = tmp_path / "page.md"
    page.write_text("```console\n$ clik solve missing.toml --out out\n```\n", encoding="utf-8")
    monkeypatch.setattr(f"{__name__}.DOCS", tmp_path)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(AssertionError, match=r"docs/page.md:1: `clik solve missing.toml"):
        run_page(Path("page.md"), tmp_path, capsys)
