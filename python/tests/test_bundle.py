"""lazyboe.Bundle: header, inspect(), and per-edge arrays that are read-only views of the
memory-mapped file."""

import numpy as np
import pytest

import lazyboe
from conftest import EDGES, THETA, tool

ARRAYS = ["q0", "qf", "duration", "command_duration", "p_lazy_prop", "p_collision",
          "p_lazy_prop_transfer", "transfer_max_error"]


def mapped_file_of(address):
    """The file whose mapping (in /proc/self/maps) holds `address`, or None."""
    with open("/proc/self/maps") as maps:
        for line in maps:
            fields = line.split()
            lo, hi = (int(x, 16) for x in fields[0].split("-"))
            if lo <= address < hi:
                return fields[5] if len(fields) > 5 else None
    return None


def test_arrays_are_read_only_views_into_the_file(bundle_path):
    b = lazyboe.Bundle(bundle_path)
    assert b.memory_mapped and len(b) == EDGES and b.dof == 7
    for name in ARRAYS:
        a = getattr(b, name)
        assert a.shape == ((EDGES, 7) if name in ("q0", "qf") else (EDGES,)), name
        assert not a.flags.writeable and not a.flags.owndata, name
        start = a.__array_interface__["data"][0]
        assert mapped_file_of(start) == str(bundle_path), name
        assert mapped_file_of(start + a.nbytes - 1) == str(bundle_path), name
        with pytest.raises(ValueError):
            a[0] = 1.0
        a.setflags(write=False)  # allowed; making it writeable is not
        with pytest.raises(ValueError):
            a.setflags(write=True)


def test_views_equal_the_datasets_read_into_memory(bundle_path):
    mapped, read = lazyboe.Bundle(bundle_path), lazyboe.Bundle(bundle_path, memory_map=False)
    assert not read.memory_mapped
    for name in ARRAYS:
        a, b = getattr(mapped, name), getattr(read, name)
        assert mapped_file_of(b.__array_interface__["data"][0]) != str(bundle_path)
        np.testing.assert_array_equal(a, b)


def test_views_keep_the_bundle_alive(bundle_path):
    q0 = lazyboe.Bundle(bundle_path).q0
    expected = lazyboe.Bundle(bundle_path, memory_map=False).q0.copy()
    np.testing.assert_array_equal(q0, expected)  # the first Bundle is gone, its mapping is not


def test_header_and_perturbation(bundle_path):
    b = lazyboe.Bundle(bundle_path)
    h = b.header
    assert h["dof"] == 7 and h["target_edges"] == EDGES and h["complete"]
    assert h["design_theta"] == THETA and h["env_name"] == "empty"
    assert h["valid"] == EDGES and h["attempts"] >= EDGES
    assert b.has_perturbation and b.perturbation_theta == THETA
    assert ((b.p_lazy_prop >= 0) & (b.p_lazy_prop <= 1)).all()
    assert (b.duration >= b.command_duration).all()


def test_unperturbed_bundle_has_no_probabilities(unperturbed_path):
    b = lazyboe.Bundle(unperturbed_path)
    assert not b.has_perturbation and b.perturbation_theta is None
    assert b.p_lazy_prop is None and b.p_collision is None


def test_command(bundle_path):
    b = lazyboe.Bundle(bundle_path)
    c = b.command(3)
    assert c["knots"].shape[1] == 7 and c["knots"].shape[0] >= 3
    assert c["duration"] == b.command_duration[3]
    assert not c["knots"].flags.writeable
    assert b.command(-1)["duration"] == b.command_duration[-1]
    with pytest.raises(IndexError, match="edge: out of range"):
        b.command(EDGES)


def test_inspect_is_the_tools(bundle_path):
    text = lazyboe.Bundle(bundle_path).inspect()
    out = tool("lazyboe-build", "--inspect", bundle_path).stdout
    assert text == out and "edges" in text


def test_session_bundle_shares_the_mapping(session, bundle_path):
    b = session.bundle
    assert b.path == str(bundle_path) and len(b) == EDGES
    assert mapped_file_of(b.q0.__array_interface__["data"][0]) == str(bundle_path)


def test_bad_files_raise_os_error(tmp_path):
    with pytest.raises(OSError, match="missing.h5"):
        lazyboe.Bundle(tmp_path / "missing.h5")
    junk = tmp_path / "junk.h5"
    junk.write_text("junk")
    with pytest.raises(OSError, match="junk.h5"):
        lazyboe.Bundle(junk)
