"""Docstrings describe code: the records of studies are in docs/experiments/, one dated file each."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "docs" / "experiments"
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


def test_every_script_is_named_in_the_readme_or_a_test():
    named = (ROOT / "README.md").read_text(encoding="utf-8") + "".join(
        p.read_text(encoding="utf-8") for p in (ROOT / "tests").rglob("test_*.py") if p.name != "test_docs.py")
    missing = [p.name for p in sorted((ROOT / "scripts").glob("*.py")) if p.stem not in named]
    assert missing == []
