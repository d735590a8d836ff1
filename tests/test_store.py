"""Tests of granplate.store: the one run store behind every cache (plate, reproduce,
verification, bench reference)."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import xarray as xr

from granplate import store
from granplate.version import __version__

PAYLOAD = {"scenario_toml": 'name = "x"\n', "t_end": repr(1e-4), "n": [1, 2.5, None]}


@pytest.fixture(autouse=True)
def _private_store(tmp_path, monkeypatch):
    """Every test has its own store directory and no size cap unless it sets one."""
    monkeypatch.setenv(store.CACHE_ENV, str(tmp_path / "store"))
    monkeypatch.delenv(store.MAX_BYTES_ENV, raising=False)


def sample_dataset() -> xr.Dataset:
    t = np.linspace(0.0, 1e-4, 5)
    return xr.Dataset(
        {"E": ("time", np.sin(t * 1e4)), "n": ("time", np.arange(5, dtype=np.int64))},
        coords={"time": t},
        attrs={"scenario_toml": 'name = "x"\n', "granplate_version": __version__},
    )


def sample_arrays() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(3)
    return {"Phi": rng.normal(size=(7, 3)), "idx": np.arange(9, dtype=np.int64), "shape": np.array([3, 7])}


# ------------------------------------------------------------------------------ identity
def test_key_is_the_sha256_of_kind_format_version_and_payload():
    """The key is a 64-hex SHA-256; key order in the payload does not matter, any other field does."""
    k = store.key("plate", PAYLOAD, 1)
    assert len(k) == 64 and int(k, 16) >= 0
    assert store.key("plate", dict(reversed(list(PAYLOAD.items()))), 1) == k
    others = {
        store.key("plate", {**PAYLOAD, "t_end": repr(2e-4)}, 1),
        store.key("plate", {**PAYLOAD, "n": [1, 2.5000000000000004, None]}, 1),  # one ulp
        store.key("reproduce", PAYLOAD, 1),
        store.key("plate", PAYLOAD, 2),
        store.key("plate", PAYLOAD, 1, version=__version__ + ".post1"),
    }
    assert k not in others and len(others) == 5
    assert store.key("plate", PAYLOAD, 1, version=__version__) == k


def test_entries_live_under_the_cache_directory_by_kind(tmp_path, monkeypatch):
    """$GRANPLATE_CACHE/KIND/[LABEL-]KEY.EXT; without the variable, ~/.cache/granplate."""
    path = store.save_json("bench-reference", PAYLOAD, 1, {"a": 1}, label="bare-plate")
    assert (
        path == tmp_path / "store" / "bench-reference" / f"bare-plate-{store.key('bench-reference', PAYLOAD, 1)}.json"
    )
    monkeypatch.delenv(store.CACHE_ENV)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert store.cache_directory() == tmp_path / "home" / ".cache" / "granplate"


# ------------------------------------------------------------------------------ round trips
def test_arrays_round_trip_bitwise():
    """Arrays come back with the same dtype, shape and bits."""
    arrays = sample_arrays()
    assert store.load_arrays("plate", PAYLOAD, 1) is None
    store.save_arrays("plate", PAYLOAD, 1, arrays)
    back = store.load_arrays("plate", PAYLOAD, 1)
    assert set(back) == set(arrays)
    for name, a in arrays.items():
        assert back[name].dtype == a.dtype and np.array_equal(back[name], a), name


def test_json_round_trip():
    """A JSON document comes back equal (floats exact)."""
    doc = {"e_shock": 0.1 + 0.2, "names": ["a", "b"], "none": None, "n": 3}
    store.save_json("verification", PAYLOAD, 1, doc)
    assert store.load_json("verification", PAYLOAD, 1) == doc


def test_netcdf_round_trip():
    """A Dataset comes back identical (values, coordinates, attributes; the key attribute removed)."""
    ds = sample_dataset()
    store.save_netcdf("reproduce", PAYLOAD, 1, ds)
    assert store.KEY_FIELD not in ds.attrs  # the caller's dataset is left alone
    back = store.load_netcdf("reproduce", PAYLOAD, 1)
    xr.testing.assert_identical(back, ds)


# ------------------------------------------------------------------------------ bad entries
SAVERS = {
    ".npz": (store.save_arrays, store.load_arrays, sample_arrays),
    ".json": (store.save_json, store.load_json, lambda: {"a": [1.5, 2]}),
    ".nc": (store.save_netcdf, store.load_netcdf, sample_dataset),
}


@pytest.mark.parametrize("suffix", SAVERS)
@pytest.mark.parametrize("damage", ["truncated", "garbage", "empty"])
def test_damaged_entry_reads_as_none_and_is_recomputed(suffix, damage):
    """A truncated, corrupt or empty entry reads as None (no exception); saving again repairs it."""
    save, load, make = SAVERS[suffix]
    path = save("k", PAYLOAD, 1, make())
    data = path.read_bytes()
    path.write_bytes({"truncated": data[: len(data) // 2], "garbage": b"\x00not an entry" * 7, "empty": b""}[damage])
    assert load("k", PAYLOAD, 1) is None

    calls = []

    def cached():
        value = load("k", PAYLOAD, 1)
        if value is None:
            calls.append(1)
            value = make()
            save("k", PAYLOAD, 1, value)
        return value

    cached()
    cached()
    assert calls == [1] and load("k", PAYLOAD, 1) is not None


@pytest.mark.parametrize("suffix", SAVERS)
def test_entry_with_another_key_inside_reads_as_none(suffix):
    """An entry file holding another key's content (renamed, copied) is refused: the key inside is compared."""
    save, load, make = SAVERS[suffix]
    other = save("k", {"other": 1}, 1, make())
    mine = store.entry_path("k", store.key("k", PAYLOAD, 1), suffix)
    mine.write_bytes(other.read_bytes())
    assert load("k", PAYLOAD, 1) is None
    assert load("k", {"other": 1}, 1) is not None


def test_another_version_or_format_misses():
    """An entry saved by another granplate version or format version is not found."""
    store.save_json("k", PAYLOAD, 1, {"a": 1})
    assert store.load_json("k", PAYLOAD, 2) is None
    assert store.load_json("k", {**PAYLOAD, "extra": True}, 1) is None
    assert store.load_json("k", PAYLOAD, 1) == {"a": 1}


# ------------------------------------------------------------------------------ atomic writes
def test_failed_write_leaves_no_partial_file(tmp_path):
    """A writer that fails halfway leaves neither the target nor a temporary file; an old file survives."""
    target = tmp_path / "out" / "result.nc"

    def half(tmp):
        tmp.write_bytes(b"partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        store.atomic_write(target, half)
    assert list(target.parent.iterdir()) == []
    store.atomic_write(target, lambda tmp: tmp.write_text("old"))
    with pytest.raises(RuntimeError):
        store.atomic_write(target, half)
    assert target.read_text() == "old" and [p.name for p in target.parent.iterdir()] == ["result.nc"]


def test_unwritable_store_only_warns(tmp_path, monkeypatch):
    """When the store cannot be written (its directory is a file), save warns and returns None."""
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a directory")
    monkeypatch.setenv(store.CACHE_ENV, str(blocker))
    with pytest.warns(UserWarning, match="could not write"):
        assert store.save_json("k", PAYLOAD, 1, {"a": 1}) is None
    assert store.load_json("k", PAYLOAD, 1) is None


# ------------------------------------------------------------------------------ housekeeping
def test_info_and_clear():
    """info counts entries and bytes per kind (temporary files excluded); clear(kind) removes that kind only."""
    paths = [store.save_json("a", {"i": i}, 1, {"x": "y" * i}) for i in range(3)]
    paths.append(store.save_arrays("b", PAYLOAD, 1, sample_arrays()))
    (paths[0].parent / ".left-over.json.123.tmp").write_text("in progress")
    info = store.info()
    assert info == {
        "a": {"entries": 3, "bytes": sum(p.stat().st_size for p in paths[:3])},
        "b": {"entries": 1, "bytes": paths[3].stat().st_size},
    }
    assert store.clear("a") == 3
    assert set(store.info()) == {"b"} and store.load_json("a", {"i": 0}, 1) is None
    assert store.clear() == 1 and store.info() == {}
    assert store.clear("never-used") == 0


def test_size_cap_removes_least_recently_used(monkeypatch):
    """Beyond $GRANPLATE_CACHE_MAX_BYTES the least recently used entries go; a read counts as a use."""
    docs = {i: {"x": "z" * 1000} for i in range(4)}
    paths = {}
    for i in range(3):
        paths[i] = store.save_json("k", {"i": i}, 1, docs[i])
        os.utime(paths[i], ns=(10**18 + i * 10**9, 10**18 + i * 10**9))  # saved in the order 0, 1, 2
    size = paths[0].stat().st_size
    assert store.load_json("k", {"i": 0}, 1) == docs[0]  # 0 is now the most recently used
    monkeypatch.setenv(store.MAX_BYTES_ENV, str(3 * size))
    store.save_json("k", {"i": 3}, 1, docs[3])  # 4 entries > 3: the oldest unused one (1) goes
    assert store.load_json("k", {"i": 1}, 1) is None
    assert all(store.load_json("k", {"i": i}, 1) == docs[i] for i in (0, 2, 3))
    assert store.info()["k"] == {"entries": 3, "bytes": 3 * size}
    assert store.prune(0) == 3 and store.info() == {}


def test_size_cap_default_and_bad_value(monkeypatch):
    """No variable: 2 GiB; an unreadable value warns and falls back to the default."""
    assert store.max_bytes() == store.DEFAULT_MAX_BYTES == 2 * 1024**3
    monkeypatch.setenv(store.MAX_BYTES_ENV, "1e6")
    assert store.max_bytes() == 10**6
    monkeypatch.setenv(store.MAX_BYTES_ENV, "lots")
    with pytest.warns(UserWarning, match="not a number"):
        assert store.max_bytes() == store.DEFAULT_MAX_BYTES


def test_json_entry_is_readable_json():
    """A JSON entry is a plain document holding its key and the stored document."""
    path = store.save_json("k", PAYLOAD, 1, {"a": 1})
    entry = json.loads(path.read_text())
    assert entry == {store.KEY_FIELD: store.key("k", PAYLOAD, 1), "doc": {"a": 1}}


def test_last_arrays_read_are_kept_while_the_file_is_unchanged(monkeypatch):
    """A second read of the same entry does not open the file; a rewritten entry is read
    again, with its new numbers."""
    store.save_arrays("plate", PAYLOAD, 1, {"a": np.arange(3.0)})
    assert np.array_equal(store.load_arrays("plate", PAYLOAD, 1)["a"], np.arange(3.0))
    real_load = np.load
    monkeypatch.setattr(np, "load", lambda *a, **k: pytest.fail("the entry was read again"))
    assert np.array_equal(store.load_arrays("plate", PAYLOAD, 1)["a"], np.arange(3.0))
    monkeypatch.setattr(np, "load", real_load)
    store.save_arrays("plate", PAYLOAD, 1, {"a": np.arange(4.0)})
    assert np.array_equal(store.load_arrays("plate", PAYLOAD, 1)["a"], np.arange(4.0))


def test_exclusive_makes_a_second_process_wait(tmp_path):
    """While one process holds an entry, another asking for it waits until it is released."""
    import subprocess
    import sys
    import time

    code = (
        "import sys, time; from granplate import store\n"
        "print('ready', flush=True)\n"
        "t0 = time.perf_counter()\n"
        "with store.exclusive('plate', {'n': 1}, 1):\n"
        "    print(time.perf_counter() - t0, flush=True)\n"
    )
    with store.exclusive("plate", {"n": 1}, 1):
        other = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env={**os.environ})
        assert other.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        assert other.poll() is None  # still waiting
    waited = float(other.communicate(timeout=60)[0])
    assert waited >= 0.9


def test_reading_an_entry_leaves_the_others_copies_valid(monkeypatch):
    """A read by another process (its mark of use) does not change a freshly used entry's
    file, so this process's copy is still used; an entry unused for longer is marked."""
    path = store.save_arrays("plate", PAYLOAD, 1, {"a": np.arange(3.0)})
    store.load_arrays("plate", PAYLOAD, 1)
    before = os.stat(path).st_mtime_ns
    store._touch(path)  # what another process's read does
    assert os.stat(path).st_mtime_ns == before
    monkeypatch.setattr(np, "load", lambda *a, **k: pytest.fail("the entry was read again"))
    assert np.array_equal(store.load_arrays("plate", PAYLOAD, 1)["a"], np.arange(3.0))
    old = before / 1e9 - 2 * store.TOUCH_INTERVAL_S
    os.utime(path, (old, old))
    store._touch(path)
    assert os.stat(path).st_mtime > old + store.TOUCH_INTERVAL_S
