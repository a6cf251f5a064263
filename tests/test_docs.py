"""Docstrings describe code, the records of studies are in docs/experiments/ (one dated file each), and
README and the docs beside it say what the code does: links that resolve, commands that parse, every
option and every module named."""

import ast
import re
import shlex
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
EXPERIMENTS = DOCS / "experiments"
DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
RECORD = re.compile(r"docs/experiments/20\d\d-\d\d-\d\d-[a-z0-9-]+\.md")    # a pointer, not a record


def dated_docstrings(source: str) -> list:
    """``(line, date)`` of each module, class or function docstring of `source` that holds a date."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            date = DATE.search(RECORD.sub("", ast.get_docstring(node, clean=False) or ""))
            if date:
                found.append((getattr(node, "lineno", 1), date.group()))
    return found


def test_no_docstring_of_the_library_or_the_scripts_holds_a_dated_record():
    files = sorted((ROOT / "ismb_lab").rglob("*.py")) + sorted((ROOT / "scripts").glob("*.py"))
    dated = [(str(path.relative_to(ROOT)), *hit) for path in files
             for hit in dated_docstrings(path.read_text(encoding="utf-8"))]
    assert dated == []


def test_the_check_finds_a_date_in_a_module_or_a_function_docstring():
    code = ('"""A tool.\n\n**First record, 2026-11-24**: C/T 85.9%."""\n\n\n'
            'def run():\n    """Measured on 2026-11-25."""\n')
    assert dated_docstrings(code) == [(1, "2026-11-24"), (6, "2026-11-25")]
    assert dated_docstrings('"""Its records: docs/experiments/2026-11-24-x.md, --seeds-from 2000."""') == []


def test_each_record_is_one_dated_markdown_file_with_a_title():
    records = sorted(EXPERIMENTS.iterdir())
    assert records
    for record in records:
        assert re.fullmatch(r"20\d\d-\d\d-\d\d-[a-z0-9-]+\.md", record.name), record.name
        assert record.read_text(encoding="utf-8").startswith("# "), record.name


def test_every_script_is_named_in_the_readme_the_docs_or_a_test():
    pages = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
    pages += [p for p in (ROOT / "tests").rglob("test_*.py") if p.name != "test_docs.py"]
    named = "".join(p.read_text(encoding="utf-8") for p in pages)
    missing = [p.name for p in sorted((ROOT / "scripts").glob("*.py")) if p.stem not in named]
    assert missing == []


# --- README and the docs beside it -----------------------------------------------------------

def test_readme_is_short_and_links_the_four_docs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 200
    linked = set(re.findall(r"\]\((docs/[a-z]+\.md)(?:#[a-z0-9-]+)?\)", readme))
    assert {f"docs/{name}.md" for name in ("architecture", "cli", "depth", "matching")} <= linked


def anchors(text: str) -> set:
    """The anchors a Markdown renderer gives `text`'s headings (lower case, punctuation dropped,
    spaces as hyphens)."""
    return {re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")
            for heading in re.findall(r"^#+ (.+)$", re.sub(r"```.*?```", "", text, flags=re.S), re.M)}


def test_every_relative_link_of_the_readme_and_the_docs_names_a_file_of_the_repository():
    broken = []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        for target, anchor in re.findall(r"\]\(([^)#:]+)(?:#([^)]*))?\)", page.read_text(encoding="utf-8")):
            path = page.parent / target
            # depth.md is written beside this page by its own change; a link to it is checked once it exists
            if not path.exists() and target.endswith("depth.md"):
                continue
            if not path.exists() or anchor and anchor not in anchors(path.read_text(encoding="utf-8")):
                broken.append(f"{page.relative_to(ROOT)}: {target}#{anchor}")
    assert broken == []


def shell_commands(text: str) -> list:
    """The ``ismb-lab`` command lines of `text`'s ```bash blocks, each as its argument list.

    Continued lines are joined, ``NAME=value`` lines define variables that later ``$NAME`` words
    use, ``NAME=value`` words before the command (its environment) are dropped, and a pipe ends it.
    """
    found = []
    for block in re.findall(r"```bash\n(.*?)```", text, re.S):
        variables = {}
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line.split(" | ")[0], comments=True)
            if len(words) == 1 and re.fullmatch(r"[A-Z_]+=\S+", words[0]):
                name, value = words[0].split("=", 1)
                variables[name] = value
                continue
            while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):
                words = words[1:]
            words = [re.sub(r"\$([A-Z_]+)", lambda m: variables[m.group(1)], w) for w in words]
            if words and words[0] == "ismb-lab":
                found.append(words[1:])
    return found


def test_shell_commands_joins_lines_expands_variables_and_drops_the_environment_and_pipes():
    block = "```bash\nD=/x\nISMB_LAB_MAX_SEEDS=3 ismb-lab match $D/l.png \\\n  r.png | head\nls\n```\n"
    assert shell_commands(block) == [["match", "/x/l.png", "r.png"]]
    assert shell_commands("```text\nismb-lab match L R\n```\n") == []


def documented_commands() -> list:
    return [(page, words) for page in ("README.md", "docs/cli.md")
            for words in shell_commands((ROOT / page).read_text(encoding="utf-8"))]


def test_the_readme_and_the_cli_reference_show_commands():
    pages = {page for page, _ in documented_commands()}
    assert pages == {"README.md", "docs/cli.md"}
    commands = {words[0] for _, words in documented_commands()}
    assert commands == {"match", "tune", "evaluate", "depth", "rectify", "calibrate", "render", "targets",
                        "course"}


@pytest.mark.parametrize("page, words", documented_commands(),
                         ids=[f"{page}-{n}-{w[0]}" for n, (page, w) in enumerate(documented_commands())])
def test_every_printed_command_parses(page, words):
    """The command's parser accepts it as printed: the command exists, and so do its options (spelled
    out), their choices and value types, and its positional arguments; not that its files exist or
    that it succeeds."""
    from ismb_lab.cli import build_parser

    build_parser().parse_args(words)
    parsers = subcommand_parsers()
    command = " ".join(words[:2]) if " ".join(words[:2]) in parsers else words[0]
    own = {o for a in parsers[command]._actions for o in a.option_strings}
    # argparse takes an unambiguous prefix of an option too: the page must spell it out
    assert [w for w in words if w.startswith("--") and w.split("=")[0] not in own] == []


def subcommand_parsers() -> dict:
    """``"match"``, ``"targets merge"``, ...: the parser of every command, from the CLI's own parser."""
    import argparse

    from ismb_lab.cli import build_parser

    def walk(parser, prefix):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            return {prefix: parser}
        return {k: v for name, child in subs[0].choices.items()
                for k, v in walk(child, f"{prefix} {name}".strip()).items()}

    return walk(build_parser(), "")


def synopses() -> dict:
    """The options each ```text synopsis of docs/cli.md names, by command (``ismb-lab CMD ...`` lines and
    the lines indented under them)."""
    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    commands = sorted(subcommand_parsers(), key=len, reverse=True)
    found = {}
    for block in re.findall(r"```text\n(.*?)```", text, re.S):
        current = None
        for line in block.splitlines():
            if line.startswith("ismb-lab "):
                rest = line[len("ismb-lab "):]
                current = next(c for c in commands if rest == c or rest.startswith(c + " "))
                found.setdefault(current, set())
            found[current] |= set(re.findall(r"(?<![\w-])--[a-z][a-z-]*", line))
    return found


def test_the_cli_reference_has_a_synopsis_of_every_option_of_every_command_and_no_other():
    parsers, named = subcommand_parsers(), synopses()
    assert set(named) == set(parsers)
    for command, parser in parsers.items():
        options = {o for a in parser._actions for o in a.option_strings if o.startswith("--")} - {"--help"}
        assert named[command] == options, command


def test_the_architecture_names_every_module():
    text = (DOCS / "architecture.md").read_text(encoding="utf-8")
    spans = set(re.findall(r"`([^`\s]+)`", text))
    spans |= {s.removeprefix("ismb_lab.") for s in spans}
    package = ROOT / "ismb_lab"
    missing = []
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        if name and name not in spans:
            missing.append(name)
    assert missing == []
