"""The metrics of every evaluation are one tuple (degrees.METRICS) that rollout, stress and the seed reader import;
the evaluation's file is run/layout.METRICS_FILE, a name that no longer clashes with it."""


def test_one_metric_tuple_and_a_file_name_apart():
    from neurosym_cli import degrees, rollout
    from neurosym_cli.run import layout
    from neurosym_cli.seeds import read
    from neurosym_cli.stages import stress

    assert rollout.METRICS is degrees.METRICS and stress.METRICS is degrees.METRICS and read.SHARED is degrees.METRICS
    assert degrees.METRICS == ("cost", "max_in", "max_out", "max_degree", "mean_degree")
    assert layout.METRICS_FILE == "metrics.json" and not hasattr(layout, "METRICS")


def test_the_evaluation_file_is_found_by_its_name(tmp_path):
    from neurosym_cli.run.layout import METRICS_FILE, RunFolder

    (tmp_path / "eval" / "tf-full").mkdir(parents=True)
    (tmp_path / "eval" / "tf-full" / METRICS_FILE).write_text("{}")
    assert RunFolder(tmp_path).metrics_files() == [tmp_path / "eval" / "tf-full" / "metrics.json"]
