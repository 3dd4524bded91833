"""``ocp-crawl init``: the shipped problem files and examples written out.

The repository's problems/ and examples/ folders are that copy, file for file.
"""
import json
import re
from pathlib import Path

import pytest

import ocp_crawl.cli.app as cli
from ocp_crawl import load_problem
from ocp_crawl.problem.shipped import (SHIPPED_DIR, SHIPPED_FOLDERS, shipped_problem,
                                       shipped_problems, write_problems)

REPO = Path(__file__).resolve().parent.parent


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.mark.parametrize("folder", sorted(SHIPPED_FOLDERS))
def test_repository_copy_is_what_init_writes(folder, tmp_path, capsys):
    """One source of truth: problems/ and examples/ at the repository root equal `ocp-crawl init`
    output."""
    assert cli.main(["init", str(tmp_path)]) == 0
    written, repo = _files(tmp_path / folder), _files(REPO / folder)
    repo = {n: b for n, b in repo.items() if not n.endswith(".pyc")}
    refresh = (f"edit ocp_crawl/data/{folder}/ (the shipped copy; new files go there too) and run "
               "'ocp-crawl init --force' at the repository root")
    assert set(written) == set(repo), (f"{folder}/ and ocp_crawl/data/{folder}/ hold different "
                                       f"files: only in {folder}/: {set(repo) - set(written)}, "
                                       f"only shipped: {set(written) - set(repo)}; {refresh}")
    differ = [n for n in written if written[n] != repo[n]]
    assert not differ, f"{folder}/ differs from ocp_crawl/data/{folder}/ in {differ}: {refresh}"
    assert len(written) >= 6


def test_every_shipped_problem_is_valid():
    for name, path in shipped_problems().items():
        if name.endswith(".toml"):
            assert load_problem(path).source == str(path)
    assert (shipped_problem("paper_gait") == shipped_problem("paper_gait.toml")
            == SHIPPED_DIR / "paper_gait.toml")
    with pytest.raises(KeyError, match="paper_gait.toml"):
        shipped_problem("no_such_problem")


def test_init_default_is_the_current_directory_and_json_lists_the_files(tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["init", "--json"]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert err == "" and data["directory"] == "."
    expected = [f"{folder}/{n}"
                for folder, src in SHIPPED_FOLDERS.items() for n in sorted(_files(src))]
    assert data["files"] == expected and any(f.startswith("examples/") for f in expected)
    assert all((tmp_path / f).is_file() for f in data["files"])
    for folder in SHIPPED_FOLDERS:  # nothing else, no temporary files
        assert (sorted(p.name for p in (tmp_path / folder).iterdir())
                == sorted(_files(SHIPPED_FOLDERS[folder])))


def test_init_refuses_to_overwrite_before_writing_anything(tmp_path, capsys):
    names = list(shipped_problems())
    (tmp_path / "problems").mkdir()
    # the last one: a refusal after writing the others would show
    mine = tmp_path / "problems" / names[-1]
    mine.write_text("# my own edits\n")
    assert cli.main(["init", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert str(mine) in err and "--force" in err and "nothing was written" in err
    assert sorted(p.name for p in (tmp_path / "problems").iterdir()) == [names[-1]]
    assert mine.read_text() == "# my own edits\n"
    # --force overwrites with the shipped bytes
    assert not (tmp_path / "examples").exists()
    assert cli.main(["init", str(tmp_path), "--force"]) == 0
    assert _files(tmp_path / "problems") == _files(SHIPPED_DIR)


def test_write_problems_python_api(tmp_path):
    files = write_problems(tmp_path / "new" / "dir")
    assert [f.name for f in files if f.parent.name == "problems"] == list(shipped_problems())
    with pytest.raises(FileExistsError) as info:
        write_problems(tmp_path / "new" / "dir")
    assert info.value.filename == str(files[0])
    assert write_problems(tmp_path / "new" / "dir", force=True) == files


def test_every_problem_file_the_readme_names_is_shipped():
    """The commands of the README and of the docs pages name problems/X; `ocp-crawl init` must write
    each (a wheel install has no other)."""
    pages = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")),
             *sorted((REPO / "docs" / "guide").glob("*.md"))]
    text = "\n".join(page.read_text(encoding="utf-8") for page in pages)
    named = set(re.findall(r"problems/([A-Za-z0-9_.-]+\.(?:toml|csv))", text))
    assert "paper_gait.toml" in named
    assert named <= set(shipped_problems()), named - set(shipped_problems())


def test_ci_runs_the_readme_test_command():
    """CI runs the test command of the README's second line (the one a new machine runs), word for
    word."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    block = readme.split("```", 2)[1].strip().splitlines()
    assert len(block) == 2 and block[1].startswith("python3 -m venv"), block
    readme_command = block[1].split("&&")[-1].strip()
    ci_lines = [line.strip()
                for line in (REPO / ".ci" / "run").read_text(encoding="utf-8").splitlines()]
    test_lines = [line for line in ci_lines if "pytest" in line and not line.startswith("#")]
    assert readme_command.startswith("python -m pytest")
    assert test_lines == [readme_command], (test_lines, readme_command)
