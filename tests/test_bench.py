"""The benchmark runs and reports its figures (speed itself is measured by `op2motion bench`, not asserted)."""

from op2motion.bench import run_bench


def test_bench_reports_every_figure(spec):
    result = run_bench(spec, n=500, repeat=1)
    assert result["poses"] == 500
    for key in ("fk_pb_40k_ms", "fk_dh_40k_ms", "pinocchio_com_40k_ms", "validate_ms", "pso_solve_ms"):
        assert result[key] > 0, key
