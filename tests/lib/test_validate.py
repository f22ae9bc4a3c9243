import numpy as np
import pytest

from ctrl_analysis._validate import (
    check_finite,
    check_in,
    check_int,
    check_matrix,
    check_nonnegative,
    check_positive,
)


def test_messages_name_argument_and_rule():
    with pytest.raises(ValueError, match=r"^R must be > 0, got -1$"):
        check_positive("R", -1)
    with pytest.raises(ValueError, match="Q must be >= 0"):
        check_nonnegative("Q", [1, -2])
    with pytest.raises(ValueError, match="a must be finite"):
        check_positive("a", float("nan"))
    with pytest.raises(TypeError, match="n0 must be an integer"):
        check_int("n0", 2.5)
    with pytest.raises(ValueError, match="n0 must be >= 2, got 1"):
        check_int("n0", 1, minimum=2)
    with pytest.raises(TypeError, match="x must be a real number"):
        check_finite("x", "abc")
    with pytest.raises(ValueError, match="method must be one of"):
        check_in("method", "x", {"rk4", "euler"})
    with pytest.raises(ValueError, match="P must be symmetric"):
        check_matrix("P", [[1, 2], [0, 1]], symmetric=True)
    with pytest.raises(ValueError, match=r"A must have shape \(2, 2\)"):
        check_matrix("A", np.eye(3), shape=(2, 2))


def test_valid_values_pass_through():
    assert check_int("n", 4.0) == 4 and check_positive("a", 2) == 2.0
    np.testing.assert_array_equal(check_matrix("A", [[1, 0], [0, 1]], square=True), np.eye(2))
    with pytest.raises(TypeError):
        check_int("n", True)


def test_check_out_dir_creates_a_writable_directory_and_refuses_a_file(tmp_path):
    from ctrl_analysis._validate import check_out_dir

    out = check_out_dir("--out", str(tmp_path / "a" / "b"))
    assert out.is_dir() and list(out.iterdir()) == []  # the probe file is gone
    (tmp_path / "f").write_text("x")
    with pytest.raises(ValueError, match="--out must be a directory, got the file"):
        check_out_dir("--out", str(tmp_path / "f"))
    with pytest.raises(ValueError, match="--out must name a directory, got an empty string"):
        check_out_dir("--out", " ")
    with pytest.raises(TypeError, match="--out must be a path"):
        check_out_dir("--out", 3)
