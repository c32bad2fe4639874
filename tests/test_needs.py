"""tests/needs.py: the public data is found beside the repository only; a missing file skips its test, names the
file, and fails the test under CI=true."""

from pathlib import Path

import pytest

from tests import needs


def test_the_public_data_is_found_beside_the_repository():
    assert needs.PUBLIC_DATA == Path(__file__).resolve().parents[1].parent / "shared" / "data"


def test_a_missing_public_file_is_skipped_and_fails_under_ci(monkeypatch, tmp_path):
    monkeypatch.setattr(needs, "PUBLIC_DATA", tmp_path)
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match=r"\.\./shared/data/mpd/x\.npz is not present"):
        needs.public_data("mpd/x.npz")
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match=r"CI=true .*\.\./shared/data/mpd/x\.npz is not present"):
        needs.public_data("mpd/x.npz")
    (tmp_path / "mpd").mkdir()
    (tmp_path / "mpd" / "x.npz").write_bytes(b"")
    assert needs.public_data("mpd/x.npz") == tmp_path / "mpd" / "x.npz"
