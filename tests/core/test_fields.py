import numpy as np
import pyopencl.array as cla
import pytest

from clpde.errors import ClpdeError
from clpde.fields import Field, Grid, PingPong, compact, index_list


@pytest.mark.parametrize("ghost", [1, 2])
def test_neumann_ghosts_mirror_the_interior(runtime, rng, ghost):
    values = rng.random((2, 5, 7)).astype(np.float32)
    grid = Grid(runtime, 7, 5, 2, ghost)
    padded = Field.from_host(grid, values).data.get()
    expected = np.pad(values, ((0, 0), (ghost, ghost), (ghost, ghost)), mode="symmetric")
    np.testing.assert_array_equal(padded, expected)


def test_dirichlet_ghosts_hold_the_value(runtime, rng):
    values = rng.random((1, 4, 6)).astype(np.float32)
    grid = Grid(runtime, 6, 4)
    padded = Field.from_host(grid, values, boundary="dirichlet", value=-3.0).data.get()
    expected = np.pad(values, ((0, 0), (1, 1), (1, 1)), constant_values=-3.0)
    np.testing.assert_array_equal(padded, expected)


def test_round_trip_and_shape_check(runtime, rng):
    values = rng.random((3, 9, 4))
    grid = Grid(runtime, 4, 9, 3)
    np.testing.assert_allclose(Field.from_host(grid, values).to_host(), values, rtol=1e-7)
    with pytest.raises(ClpdeError, match="shape"):
        Field.from_host(grid, values[:, :8])
    with pytest.raises(ClpdeError, match="neumann"):
        Field.from_host(grid, values).fill_ghosts("periodic")


def test_ping_pong_swaps_buffers(runtime, rng):
    grid = Grid(runtime, 4, 4)
    pair = PingPong(Field.from_host(grid, rng.random((1, 4, 4))))
    first, second = pair.cur, pair.nxt
    assert first.data.data.int_ptr != second.data.data.int_ptr
    pair.swap()
    assert pair.cur is second and pair.nxt is first


def test_reductions_match_numpy_and_ignore_ghosts(runtime, rng):
    a = rng.normal(size=(2, 33, 17))
    b = rng.normal(size=(2, 33, 17))
    grid = Grid(runtime, 17, 33, 2)
    fa, fb = Field.from_host(grid, a), Field.from_host(grid, b)
    a32, b32 = a.astype(np.float32).astype(float), b.astype(np.float32).astype(float)
    axes = (1, 2)
    checks = {
        "sum": a32.sum(axis=axes),
        "sumsq": (a32**2).sum(axis=axes),
        "maxabsdiff": np.abs(a32 - b32).max(axis=axes),
        "sumsqdiff": ((a32 - b32) ** 2).sum(axis=axes),
        "maxabs": np.abs(a32).max(axis=axes),
        "min": a32.min(axis=axes),
        "max": a32.max(axis=axes),
    }
    for op, expected in checks.items():
        np.testing.assert_allclose(fa.reduce(op, fb), expected, rtol=1e-5, atol=1e-5, err_msg=op)
    assert fa.max_abs_diff(fb) == pytest.approx(checks["maxabsdiff"].max(), rel=1e-6)
    np.testing.assert_allclose(fa.norm(), np.sqrt(checks["sumsq"]), rtol=1e-5)


@pytest.mark.parametrize("density", [0.0, 0.007, 0.23, 1.0])
def test_index_list_is_the_sorted_padded_indices_of_the_mask(runtime, rng, density):
    ny, nx = 61, 83
    mask = rng.random((ny, nx)) < density
    grid = Grid(runtime, nx, ny)
    lst = index_list(grid, mask)
    padded = np.zeros((ny + 2, nx + 2), bool)
    padded[1:-1, 1:-1] = mask
    expected = np.flatnonzero(padded)
    assert lst.n == expected.size
    np.testing.assert_array_equal(lst.indices.get()[: lst.n], expected)


def test_compaction_spans_many_chunks(runtime, rng):
    flat = (rng.random(50_000) < 0.1).astype(np.uint8)
    lst = compact(runtime, cla.to_device(runtime.queue, flat))
    np.testing.assert_array_equal(lst.indices.get()[: lst.n], np.flatnonzero(flat))


@pytest.mark.parametrize("n", [1, 7, 9, 4095, 4097, 12_345])
@pytest.mark.parametrize("density", [0.0, 0.01, 0.3, 1.0])
def test_compaction_of_sparse_and_ragged_masks(runtime, rng, n, density):
    """write_chunks skips zero 8-byte words: lengths off the words and the chunks, nonzero
    values other than 1, empty and full masks all give numpy's list."""
    flat = (rng.random(n) < density) * rng.integers(1, 256, n).astype(np.uint8)
    lst = compact(runtime, cla.to_device(runtime.queue, flat.astype(np.uint8)))
    assert lst.n == np.count_nonzero(flat)
    np.testing.assert_array_equal(lst.indices.get()[: lst.n], np.flatnonzero(flat))


def test_list_kernel_touches_only_listed_cells(runtime, rng):
    ny, nx = 20, 30
    mask = rng.random((ny, nx)) < 0.3
    grid = Grid(runtime, nx, ny, 2)
    src = Field.from_host(grid, rng.random((2, ny, nx)))
    dst = Field.from_host(grid, np.zeros((2, ny, nx)))
    lst = index_list(grid, mask)
    grid.launch_list(
        grid.kernel("common/fields.cl", "fields_copy_listed"), lst, src.data.data, dst.data.data
    )
    out = dst.to_host()
    expected = np.where(mask[None], src.to_host(), 0)
    np.testing.assert_array_equal(out, expected)
