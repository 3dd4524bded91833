"""``ocp-crawl init``: the shipped problem files written out; the repository's problems/ is that copy."""
import json
import re
from pathlib import Path

import pytest

import ocp_crawl.cli.app as cli
from ocp_crawl import load_problem
from ocp_crawl.problem.shipped import SHIPPED_DIR, shipped_problem, shipped_problems, write_problems

REPO = Path(__file__).resolve().parent.parent


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_repository_problems_are_what_init_writes(tmp_path, capsys):
    """One source of truth: problems/ at the repository root equals `ocp-crawl init` output, file for file."""
    assert cli.main(["init", str(tmp_path)]) == 0
    written, repo = _files(tmp_path / "problems"), _files(REPO / "problems")
    assert set(written) == set(repo), (
        f"problems/ and ocp_crawl/data/problems/ hold different files: only in problems/: {set(repo) - set(written)}, "
        f"only shipped: {set(written) - set(repo)}; add new problem files to ocp_crawl/data/problems/ and run "
        "'ocp-crawl init --force' at the repository root")
    differ = [n for n in written if written[n] != repo[n]]
    assert not differ, (f"problems/ differs from ocp_crawl/data/problems/ in {differ}: edit the package copy and run "
                        "'ocp-crawl init --force' at the repository root")
    assert "paper_gait.toml" in written and len(written) >= 6


def test_every_shipped_problem_is_valid():
    for name, path in shipped_problems().items():
        if name.endswith(".toml"):
            assert load_problem(path).source == str(path)
    assert shipped_problem("paper_gait") == shipped_problem("paper_gait.toml") == SHIPPED_DIR / "paper_gait.toml"
    with pytest.raises(KeyError, match="paper_gait.toml"):
        shipped_problem("no_such_problem")


def test_init_default_is_the_current_directory_and_json_lists_the_files(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["init", "--json"]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert err == "" and data["directory"] == "."
    assert sorted(data["files"]) == sorted(f"problems/{n}" for n in shipped_problems())
    assert all((tmp_path / f).is_file() for f in data["files"])
    assert sorted(p.name for p in (tmp_path / "problems").iterdir()) == sorted(shipped_problems())  # no temp files


def test_init_refuses_to_overwrite_before_writing_anything(tmp_path, capsys):
    names = list(shipped_problems())
    (tmp_path / "problems").mkdir()
    mine = tmp_path / "problems" / names[-1]  # the last one: a refusal after writing the others would show
    mine.write_text("# my own edits\n")
    assert cli.main(["init", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert str(mine) in err and "--force" in err and "nothing was written" in err
    assert sorted(p.name for p in (tmp_path / "problems").iterdir()) == [names[-1]]
    assert mine.read_text() == "# my own edits\n"
    # --force overwrites with the shipped bytes
    assert cli.main(["init", str(tmp_path), "--force"]) == 0
    assert _files(tmp_path / "problems") == _files(SHIPPED_DIR)


def test_write_problems_python_api(tmp_path):
    files = write_problems(tmp_path / "new" / "dir")
    assert [f.name for f in files] == list(shipped_problems())
    with pytest.raises(FileExistsError) as info:
        write_problems(tmp_path / "new" / "dir")
    assert info.value.filename == str(files[0])
    assert write_problems(tmp_path / "new" / "dir", force=True) == files


def test_every_problem_file_the_readme_names_is_shipped():
    """The README's commands name problems/X; `ocp-crawl init` must write each (a wheel install has no other)."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    named = set(re.findall(r"problems/([A-Za-z0-9_.-]+\.(?:toml|csv))", readme))
    assert "paper_gait.toml" in named
    assert named <= set(shipped_problems()), named - set(shipped_problems())
