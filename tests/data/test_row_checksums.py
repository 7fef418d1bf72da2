"""Row checksums of raw columns (see stable_worldmodel/data/_rowsum.py): written with the rows, checked
on every read path, a flipped byte is a DatasetFormatError; files without them read and append as before."""

from __future__ import annotations

import itertools
import logging
import os
import time

import h5py
import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel.data import HDF5Dataset, _rowsum, load_dataset
from stable_worldmodel.data.writer import HDF5Writer
from stable_worldmodel.errors import ConfigError, DatasetFormatError

RAW = (keys.ACTION, keys.STATE, keys.STEP_IDX, keys.TERMINATED)  # with 24x24 images, pixels are compressed
IMAGE = (24, 24)
LENGTHS = (5, 7, 4)


def _reference(row: bytes, index: int) -> int:
    """The checksum of one row, in plain Python (the definition in _rowsum's docstring)."""
    size = next(s for s in (1, 2, 4, 8) if s >= min(len(row), 8))  # bytes kept
    row += bytes(-len(row) % 4)
    words = [int.from_bytes(row[i : i + 4], "little") for i in range(0, len(row), 4)]
    mult = [int(m) for m in _rowsum.multipliers(len(words))]
    total = sum(m * w for m, w in zip(mult, words, strict=True)) + (index + 1) * int(_rowsum.ROW_MULTIPLIER)
    return int.from_bytes((total % 2 ** (8 * size)).to_bytes(size, "little"), "little", signed=True)


def _flip(path, column: str, row: int, at: int = 0, bit: int = 0x10) -> None:
    """Flip ``bit`` of byte ``at`` of row ``row`` of raw ``column``, on disk."""
    with h5py.File(path) as f:
        dset = f[column]
        row_bytes = dset.dtype.itemsize * int(np.prod(dset.shape[1:], dtype=np.int64))
        if dset.chunks is None:
            offset = dset.id.get_offset() + row * row_bytes
        else:
            chunk = row // dset.chunks[0]
            offset = dset.id.get_chunk_info_by_coord((chunk * dset.chunks[0],) + (0,) * (dset.ndim - 1)).byte_offset
            offset += (row - chunk * dset.chunks[0]) * row_bytes
    raw = bytearray(path.read_bytes())
    raw[offset + at] ^= bit
    path.write_bytes(bytes(raw))


@pytest.fixture
def recorded(make_h5):
    return make_h5(LENGTHS, image=IMAGE)


# -- the layout ---------------------------------------------------------------------------------
def test_new_file_has_a_checksum_per_row_of_each_raw_column(recorded):
    with h5py.File(recorded) as f:
        sums = sorted(n for n in f if _rowsum.is_companion(n))
        assert sums == sorted(_rowsum.companion(c) for c in RAW)  # none for the gzip-compressed pixels
        for col in RAW:
            dset = f[_rowsum.companion(col)]
            assert dset.shape == (sum(LENGTHS),) and dset.compression is None
            assert dset.dtype == {keys.TERMINATED: np.int8}.get(col, np.int64)  # a 1-byte row: a 1-byte checksum
            rows = f[col][:]
            assert dset[:].tolist() == [_reference(rows[i].tobytes(), i) for i in range(len(rows))]


def test_readers_never_list_checksums_as_columns(recorded, tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from stable_worldmodel.cli import app
    from stable_worldmodel.data import dataset_info

    columns = sorted((*RAW, keys.PIXELS))
    assert sorted(HDF5Dataset(recorded).column_names) == columns
    assert sorted(load_dataset(str(recorded)).column_names) == columns
    monkeypatch.setenv("STABLEWM_HOME", str(tmp_path))
    assert sorted(dataset_info(recorded.stem)["columns"]) == columns
    shown = CliRunner().invoke(app, ["show", "dataset", recorded.stem])
    assert shown.exit_code == 0 and "checksum" not in shown.stdout and keys.STATE in shown.stdout
    with pytest.raises(KeyError, match="checksum:state"):
        HDF5Dataset(recorded, keys_to_load=[_rowsum.companion(keys.STATE)])


def test_a_reader_of_0_1_1_reads_the_checksums_as_one_more_column(recorded):
    """0.1.1 lists ``f.keys()`` minus the index and reads ``f[key][start:end]`` into torch: no crash."""
    import torch

    with h5py.File(recorded, "r") as f:
        names = [k for k in f.keys() if k not in ("ep_len", "ep_offset")]
        item = {k: torch.from_numpy(f[k][5:9][::2]) for k in names}
    assert item[_rowsum.companion(keys.STATE)].dtype == torch.int64 and item[keys.STATE].shape == (2, 2)


def test_checksum_false_writes_none_and_checksum_must_be_a_bool(make_h5, tmp_path):
    path = make_h5(LENGTHS, image=IMAGE, checksum=False)
    with h5py.File(path) as f:
        assert not any(_rowsum.is_companion(n) for n in f)
    with pytest.raises(ConfigError, match="checksum to be True or False, got 'yes'"):
        HDF5Writer(tmp_path / "x.h5", checksum="yes")


# -- the hash -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "rows",
    [
        np.arange(12, dtype=np.float32).reshape(6, 2),  # 2 words: column by column
        np.arange(60, dtype=np.float64).reshape(6, 10),  # 20 words: matmul
        np.array([True, False, True]),  # 1 byte, padded
        np.arange(30, dtype=np.int16).reshape(3, 5, 2),  # 20 bytes
        np.arange(21, dtype=np.uint8).reshape(3, 7),  # 7 bytes, padded
        np.arange(5, dtype=np.float32),  # 4 bytes: a 4-byte checksum
        np.arange(6, dtype=np.int16).reshape(3, 2),
    ],
)
def test_row_checksums_match_the_definition(rows):
    got = _rowsum.row_checksums(rows, 40)
    assert got.dtype == _rowsum.checksum_dtype(rows.shape[1:], rows.dtype)
    assert got.tolist() == [_reference(rows[i].tobytes(), 40 + i) for i in range(len(rows))]


def test_no_two_multipliers_can_cancel_a_pair_of_bit_flips():
    """Flips at bit b of words j, k cancel iff M_j = -+M_k (mod 2**(64-b)), b <= 31: none is, mod 2**33."""
    mult = _rowsum.multipliers(1024).astype(object) % 2**33
    assert len(set(mult.tolist()) | {(-m) % 2**33 for m in mult.tolist()}) == 2 * len(mult)
    assert all(m % 2 for m in _rowsum.multipliers(1024).tolist())


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_a_row_of_up_to_4_bytes_cannot_change_without_its_checksum(dtype):
    """Narrow checksums keep as many bytes as the row: every value of the row has its own."""
    values = np.arange(np.iinfo(dtype).max + 1, dtype=np.int64).astype(dtype)
    sums = np.stack([_rowsum.row_checksums(values[i : i + 1], 7)[0] for i in range(0, len(values), 97)])
    assert len(np.unique(sums)) == len(sums)
    every = np.array([_rowsum.row_checksums(v[None], 7)[0] for v in values]) if dtype is np.uint8 else None
    assert every is None or len(np.unique(every)) == 256


def test_every_one_and_two_bit_flip_of_a_row_is_caught():
    row = np.random.default_rng(0).standard_normal(2)  # 16 bytes: 128 bits, 8128 pairs
    bits = np.unpackbits(row.view(np.uint8))
    pairs = [(i,) for i in range(len(bits))] + list(itertools.combinations(range(len(bits)), 2))
    flipped = np.repeat(bits[None], len(pairs), axis=0)
    for n, pair in enumerate(pairs):
        flipped[n, list(pair)] ^= 1
    damaged = np.packbits(flipped, axis=1).view(np.float64)
    good = _rowsum.row_checksums(row[None], 9)[0]
    sums = np.concatenate([_rowsum.row_checksums(damaged[i : i + 1], 9) for i in range(len(damaged))])
    assert not np.any(sums == good)
    moved = _rowsum.row_checksums(row[None], 10)[0]  # the same row read at another index
    assert moved != good


# -- a flipped byte is an error on every read path -----------------------------------------------
READS = {
    "preload": lambda p: HDF5Dataset(p),
    "cache": lambda p: HDF5Dataset(p, preload=False, keys_to_cache=[keys.STATE]),
    "column": lambda p: HDF5Dataset(p, preload=False).get_col_data(keys.STATE),
    "item": lambda p: HDF5Dataset(p, preload=False, num_steps=2)[6],
    "batch": lambda p: HDF5Dataset(p, preload=False, num_steps=2).__getitems__([0, 6, 9]),
    "episode": lambda p: HDF5Dataset(p, preload=False).load_episode(1),
    "chunk": lambda p: HDF5Dataset(p, preload=False).load_chunk([1], 0, 3),
    "rows": lambda p: HDF5Dataset(p, preload=False).get_row_data([7]),
    "load_dataset": lambda p: load_dataset(str(p)).get_col_data(keys.STATE),
}


@pytest.mark.parametrize("read", READS)
def test_a_flipped_byte_in_a_committed_row_fails_every_read_path(recorded, read):
    _flip(recorded, keys.STATE, row=7, at=3)
    damaged = r"row 7 of column 'state' in .*synth\.h5 does not match its checksum.*restore it"
    with pytest.raises(DatasetFormatError, match=damaged):
        READS[read](recorded)
    ds = HDF5Dataset(recorded, preload=False, keys_to_load=[keys.ACTION])  # the other columns still read
    assert ds.get_col_data(keys.ACTION).shape == (16, 2)


def test_a_flipped_byte_in_a_sharded_dataset_names_the_shard_and_its_row(tmp_path, synth):
    folder = tmp_path / "sharded"
    for shard in range(2):
        with HDF5Writer(folder / f"shard_{shard:05d}.h5") as w:
            w.write_episodes([synth(2 * shard + e, 4, IMAGE) for e in range(2)])
    _flip(folder / "shard_00001.h5", keys.STEP_IDX, row=5)
    with pytest.raises(DatasetFormatError, match=r"row 5 of column 'step_idx' in .*shard_00001\.h5"):
        HDF5Dataset(folder, preload=False)[13]  # row 5 of the second shard
    assert HDF5Dataset(folder / "shard_00000.h5").get_col_data(keys.STEP_IDX).tolist() == [0, 1, 2, 3] * 2


def test_several_damaged_rows_are_listed(recorded):
    for row in (2, 3, 11):
        _flip(recorded, keys.ACTION, row=row)
    with pytest.raises(DatasetFormatError, match=r"row 2 of column 'action' .* \(nor do 2 more: 3, 11\)"):
        HDF5Dataset(recorded)


def test_a_flipped_checksum_is_an_error_too(recorded):
    _flip(recorded, _rowsum.companion(keys.TERMINATED), row=4)
    with pytest.raises(DatasetFormatError, match="row 4 of column 'terminated'"):
        HDF5Dataset(recorded)


def test_a_flipped_byte_in_a_compressed_column_is_the_same_error(recorded):
    with h5py.File(recorded) as f:
        chunk = f[keys.PIXELS].id.get_chunk_info(6)
    raw = bytearray(recorded.read_bytes())
    raw[chunk.byte_offset + chunk.size // 2] ^= 0x10
    recorded.write_bytes(bytes(raw))
    ds = HDF5Dataset(recorded, preload=False)
    ds.get_col_data(keys.STATE)
    with pytest.raises(DatasetFormatError, match=r"damaged chunk in rows .* of column 'pixels' of .*synth\.h5"):
        ds.get_col_data(keys.PIXELS)


@pytest.mark.parametrize("column, entry", [(keys.EP_OFFSET, 1), (keys.EP_OFFSET, 2), (keys.EP_LEN, 0)])
def test_a_flipped_index_entry_is_an_error(recorded, column, entry):
    _flip(recorded, column, row=entry)
    with pytest.raises(DatasetFormatError, match=r"synth\.h5"):
        HDF5Dataset(recorded)


def test_an_index_entry_flipped_into_a_gap_between_episodes_is_an_error(recorded):
    _flip(recorded, keys.EP_LEN, row=1, bit=0x01)  # 7 -> 6: rows 11:12 would belong to no episode
    gap = r"of .*synth\.h5 one after the other .* ep_offset\[2\] = 12 where the episodes before it end at row 11"
    with pytest.raises(DatasetFormatError, match=gap):
        HDF5Dataset(recorded)


def test_rows_past_the_committed_ones_are_not_checked(recorded):
    with h5py.File(recorded, "a") as f:  # rows of a killed commit: no checksum, or a stale one
        for col in (keys.STATE, _rowsum.companion(keys.STATE)):
            f[col].resize(f[col].shape[0] + 3, axis=0)
    ds = HDF5Dataset(recorded, preload=False)
    assert ds.get_col_data(keys.STATE).shape == (16, 2) and len(ds[len(ds) - 1][keys.STATE]) == 1


# -- each chunk is hashed once per reader ------------------------------------------------------------
def test_each_block_is_hashed_once_per_reader(make_h5, monkeypatch):
    path = make_h5((300,) * 10, image=IMAGE)  # 3000 rows: several 1024-row chunks of state
    hashed = []
    real = _rowsum.row_checksums
    monkeypatch.setattr(_rowsum, "row_checksums", lambda rows, start: hashed.append(len(rows)) or real(rows, start))
    ds = HDF5Dataset(path, preload=False, keys_to_load=[keys.STATE], num_steps=4)
    for i in np.random.default_rng(0).integers(0, len(ds), 200):
        ds[int(i)]
    assert sum(hashed) == 3000
    ds.get_col_data(keys.STATE)
    ds.load_episode(4)
    assert sum(hashed) == 3000  # checked already: free
    HDF5Dataset(path, preload=False, keys_to_load=[keys.STATE]).get_col_data(keys.STATE)
    assert sum(hashed) == 6000  # another reader checks for itself


def test_a_read_covering_part_of_a_chunk_checks_that_part(make_h5, monkeypatch):
    path = make_h5((1500,) * 2, image=IMAGE)
    hashed = []
    real = _rowsum.row_checksums
    monkeypatch.setattr(
        _rowsum, "row_checksums", lambda rows, start: hashed.append((start, len(rows))) or real(rows, start)
    )
    ds = HDF5Dataset(path, preload=False)
    ds._rows(keys.STATE, 1000, 2100)  # parts of chunks 0 and 2, all of chunk 1
    assert hashed == [(1000, 1100)]
    ds._rows(keys.STATE, 1024, 2048)
    assert hashed == [(1000, 1100)]  # chunk 1: done
    ds._rows(keys.STATE, 1000, 1030)
    assert hashed[-1] == (1000, 24)


# -- writing: resume, append, old files ------------------------------------------------------------
def _read_back(path, synth, lengths, image=IMAGE) -> None:
    ds = HDF5Dataset(path, preload=False)
    assert ds.lengths.tolist() == list(lengths)
    for col in (*RAW, keys.PIXELS):
        expected = np.concatenate([synth(e, n, image)[col] for e, n in enumerate(lengths)])
        np.testing.assert_array_equal(ds.get_col_data(col), expected, err_msg=col)


def test_resume_and_append_keep_the_checksums_consistent(recorded, synth):
    with h5py.File(recorded, "a") as f:  # a killed commit left rows and checksums past the committed ones
        for col in (*RAW, *map(_rowsum.companion, RAW)):
            f[col].resize(f[col].shape[0] + 5, axis=0)
            f[col][-5:] = f[col][:5]
    with HDF5Writer(recorded) as w:
        w.write_episodes([synth(3, 3, IMAGE)], next_seed=4)
    with HDF5Writer(recorded) as w:
        w.write_episodes([synth(4, 6, IMAGE), synth(5, 2, IMAGE)])
    lengths = (*LENGTHS, 3, 6, 2)
    _read_back(recorded, synth, lengths)
    with h5py.File(recorded) as f:
        end = sum(lengths)
        for col in RAW:
            assert (f[_rowsum.companion(col)][:end] == _rowsum.row_checksums(f[col][:end], 0)).all()


def test_checksums_are_of_the_rows_as_stored(tmp_path):
    """HDF5 casts an episode of another dtype (saturating integers); the checksum is of what it stored."""
    path = tmp_path / "cast.h5"
    with HDF5Writer(path) as w:
        w.write_episodes([{"small": np.zeros(3, np.int16), "x": np.zeros((3, 2), np.float64)}])
        w.write_episodes([{"small": np.array([70000, -5]), "x": np.ones((2, 2), np.float32)}])
    ds = HDF5Dataset(path)
    assert ds.get_col_data("small").tolist() == [0, 0, 0, 32767, -5]


def test_files_without_checksums_still_read_and_append(make_h5, synth):
    path = make_h5(LENGTHS, image=IMAGE, checksum=False)
    with HDF5Writer(path) as w:  # checksum=True (default): a file keeps what it was created with
        w.write_episodes([synth(3, 4, IMAGE)])
    with h5py.File(path) as f:
        assert not any(_rowsum.is_companion(n) for n in f)
    _read_back(path, synth, (*LENGTHS, 4))


def test_a_file_in_the_0_0_3_layout_still_reads_and_appends(tmp_path, synth):
    path = tmp_path / "old.h5"
    episodes = [synth(e, n, IMAGE) for e, n in enumerate(LENGTHS)]
    with h5py.File(path, "w", libver="latest") as f:  # plain h5py as 0.0.3 wrote it: no checksums, a row per chunk
        for col in episodes[0]:
            data = np.concatenate([ep[col] for ep in episodes])
            f.create_dataset(col, data=data, maxshape=(None, *data.shape[1:]), chunks=(1, *data.shape[1:]))
        f.create_dataset(keys.EP_LEN, data=np.asarray(LENGTHS, np.int32), maxshape=(None,))
        f.create_dataset(keys.EP_OFFSET, data=np.asarray([0, 5, 12], np.int64), maxshape=(None,))
    _read_back(path, synth, LENGTHS)
    with HDF5Writer(path) as w:
        w.write_episodes([synth(3, 2, IMAGE)])
    _read_back(path, synth, (*LENGTHS, 2))


def test_rows_appended_without_checksums_by_another_program(recorded, synth, caplog):
    """Rows past the checksums' end (another writer) read unchecked; ours appends no checksum after a gap."""
    with h5py.File(recorded, "a") as f:
        extra = synth(3, 3, IMAGE)
        for col, value in extra.items():
            f[col].resize(16 + 3, axis=0)
            f[col][16:] = value
        for col, value in ((keys.EP_LEN, 3), (keys.EP_OFFSET, 16)):
            f[col].resize(4, axis=0)
            f[col][3] = value
    _read_back(recorded, synth, (*LENGTHS, 3))
    with caplog.at_level(logging.WARNING), HDF5Writer(recorded) as w:
        w.write_episodes([synth(4, 2, IMAGE)])
    assert "rows 16:19 of column 'state' have no checksum" in caplog.text
    _read_back(recorded, synth, (*LENGTHS, 3, 2))
    with h5py.File(recorded) as f:
        assert f[_rowsum.companion(keys.STATE)].shape == (16,)


def test_every_state_a_kill_can_leave_has_checksums_for_every_committed_row(tmp_path, monkeypatch, synth):
    """The file after each write of the writer (what a ``kill -9`` leaves): every committed row checks."""
    from stable_worldmodel.data import _superblock

    path = tmp_path / "steps.h5"
    states = []

    class Recording(_superblock.SealedFile):
        def _pwrite(self, view, pos):
            super()._pwrite(view, pos)
            if path.exists():
                states.append((os.pread(self._fd, 1 << 30, 0), committed[0]))

    monkeypatch.setattr(_superblock, "SealedFile", Recording)
    committed = [0]
    for session in ((0, 1), (2,)):  # create, then resume
        with HDF5Writer(path) as w:
            for ep in session:
                w.write_episodes([synth(ep, 3 + ep, IMAGE)], next_seed=ep + 1)
                committed[0] += 1
    monkeypatch.undo()
    assert len(states) > 20
    copy = tmp_path / "state.h5"
    for i, (raw, done) in enumerate(states):
        copy.write_bytes(raw)
        ds = HDF5Dataset(copy, preload=False)
        assert ds.num_episodes >= done, f"state {i}"
        for col in RAW:
            ds.get_col_data(col)  # raises on a row that fails its checksum
        ds.close()


def _record_forever(path, synth):  # pragma: no cover - runs in a forked child
    try:
        with HDF5Writer(path) as w:
            ep = 0
            while True:
                w.write_episodes([synth(ep, 2 + ep % 5, IMAGE)], next_seed=ep + 1)
                ep += 1
                time.sleep(0.002)
    finally:
        os._exit(1)


def test_a_live_reader_checks_every_row_it_sees(tmp_path, synth):
    """While a writer appends, a reader's committed rows all have checksums, and they hold."""
    import multiprocessing
    import signal

    path = tmp_path / "live.h5"
    proc = multiprocessing.get_context("fork").Process(target=_record_forever, args=(path, synth), daemon=True)
    proc.start()
    try:
        deadline = time.time() + 10
        while not path.exists() and time.time() < deadline:
            time.sleep(0.005)
        seen = []
        while len(seen) < 20 or seen[-1] == seen[0]:
            ds = HDF5Dataset(path, preload=False)
            for col in RAW:
                assert ds._verified[0][col].limit == ds.num_rows
                ds.get_col_data(col)
            seen.append(ds.num_rows)
            ds.close()
            assert time.time() < deadline + 10, "the writer appended nothing"
        assert proc.is_alive()
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.join()
