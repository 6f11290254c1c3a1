"""The benchmark runs and reports its figures (speed itself is measured by `op2motion bench`, not asserted)."""

from op2motion.bench import run_bench


def test_bench_reports_both_models(spec):
    result = run_bench(spec, n=500, repeat=1)
    assert result["poses"] == 500
    assert result["fk_pb_40k_ms"] > 0 and result["fk_dh_40k_ms"] > 0
