"""gpo.io.outputs' writers: what they write reads back, into a folder made for it, with nothing else left behind."""

import json

from gpo.io.outputs import write_json, write_text


def test_write_json_makes_the_folder_and_reads_back(tmp_path):
    target = tmp_path / "results" / "run.json"
    document = {"runs": [{"preset": "long1", "final_error_percent": 0.035}], "summary": {"met": True}}
    assert write_json(target, document) == target
    assert json.loads(target.read_text()) == document
    assert target.read_text().endswith("}\n")
    assert [path.name for path in (tmp_path / "results").iterdir()] == ["run.json"]


def test_write_text_replaces_a_file_whole(tmp_path):
    target = tmp_path / "note.txt"
    write_text(target, "a longer first text\n")
    write_text(target, "short\n")
    assert target.read_text() == "short\n"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["note.txt"]
