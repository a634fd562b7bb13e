"""`causalplan batch`: a file with no trials in it is invalid input, said on the screen, not only in the verdicts."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.cli.test_cli import run, write


@pytest.mark.parametrize(
    ("name", "content", "code", "says"),
    [
        ("empty.jsonl", b"", "no_trials", "is empty: there are no trials to judge"),
        ("blank.jsonl", b"\n  \n\n", "no_trials", "is empty: there are no trials to judge"),
        ("binary.jsonl", b"\x7fELF\x02\x01\x01\x00\x00\x00" + bytes(range(256)), "unreadable_trials", "is not text"),
        ("empty_list.json", b"[]\n", "no_trials", "holds no trials"),
        ("malformed.yaml", b"- {id: a, model: [\n", "unreadable_trials", "The batch file could not be read"),
    ],
)
def test_a_file_without_trials_exits_2_saying_why_and_writes_nothing(
    tmp_path: Path, name: str, content: bytes, code: str, says: str
) -> None:
    trials = tmp_path / name
    trials.write_bytes(content)
    out = tmp_path / "out"
    result = run("batch", trials, "--out", out)
    assert result.exit_code == 2
    assert f"error[{code}]: {trials}" in result.stderr and says in result.stderr
    assert not out.exists()


def test_a_line_that_cannot_be_read_is_an_invalid_trial_and_the_batch_goes_on(tmp_path: Path) -> None:
    trials = write(tmp_path, "trials.jsonl", "not json\n")
    out = tmp_path / "out"
    result = run("batch", trials, "--out", out, "--no-simulate")
    assert result.exit_code == 0
    assert "invalid" in result.stdout and (out / "verdicts.json").exists()


def test_batch_help_gives_its_exit_codes() -> None:
    said = " ".join(run("batch", "--help").output.split())
    assert "Exit 0 when the verdicts are written, whatever they are; 2 for invalid input." in said


def test_an_entry_whose_id_is_file_is_a_trial_not_the_whole_file(tmp_path: Path) -> None:
    trials = write(tmp_path, "trials.json", '[{"id": "file", "model": {}}]\n')
    out = tmp_path / "out"
    result = run("batch", trials, "--out", out, "--no-simulate")
    assert result.exit_code == 0, result.stderr
    assert "invalid" in result.stdout and (out / "verdicts.json").exists()
