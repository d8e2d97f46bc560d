"""The trade study's tables and text (screening.report.tradeoff_text): the statement of a rule in each of its three
cases (no failure, no safe range, a safe range then a failure), the recommendation picking the loosest coupled rule
and the tightest condensed one, and the CSV table read back with the standard library."""

import csv

import pytest

from screening.report import tradeoff_text as tt


def _rule(**over):
    rule = dict(group="all", reference="coupled", threshold=0.1, n=5, n_pass=5, p_max=0.8, p_safe=0.8, n_safe=5,
                fail_name="", fail_p=float("nan"), fail_error=float("nan"), n_margin=0, margin_bound=0.2)
    rule.update(over)
    return rule


def test_a_rule_without_failure_holds_at_every_tested_point():
    text = tt.rule_text(_rule(), "peak", "var_theta")
    assert text == ("[all] SL within 10% of coupled MCS (peak var_theta): at every tested point (5, SL peak "
                    "p_uplift up to 0.8); 5/5 pass overall")


def test_a_rule_failing_at_the_lowest_level_has_no_safe_range():
    text = tt.rule_text(_rule(n_safe=0, n_pass=2, fail_name="a", fail_p=0.05, fail_error=-0.3), "time_avg",
                        "var_theta_dot")
    assert text.startswith("[all] SL within 10% of coupled MCS (time-averaged var_theta_dot): no safe p_uplift range")
    assert "first failure at p = 0.05 (a: -30 %)" in text and text.endswith("2/5 pass overall")


def test_a_rule_with_a_safe_range_names_its_bound_first_failure_and_margin_rule():
    text = tt.rule_text(_rule(n_safe=3, p_safe=0.4, n_pass=4, fail_name="c", fail_p=0.6, fail_error=0.5,
                              n_margin=2), "worst", "var_theta")
    assert "(peak and time-averaged var_theta): for SL peak p_uplift <= 0.4 (3 tested points, all pass)" in text
    assert text.endswith("first failure at p = 0.6 (c: +50 %); 4/5 pass overall; margin rule min_k_eq/k_eq(0) > "
                         "0.20 covers 2 points")


def test_the_recommendation_takes_the_loosest_coupled_and_the_tightest_condensed_threshold():
    rules = [_rule(threshold=0.1, n_safe=2, p_safe=0.2, fail_name="x"), _rule(threshold=0.25),
             _rule(reference="condensed", threshold=0.05, n_safe=0, fail_name="y"),
             _rule(reference="condensed", threshold=0.2), _rule(group="stiff", threshold=0.5)]
    text = tt.recommendation(rules)
    assert text.startswith("Use SL alone for every tested SL peak p_uplift (up to 0.8): there it stays within 25% "
                           "of coupled MCS")
    assert "(SL vs condensed MCS) stays within 5% for no tested SL peak p_uplift" in text and text.endswith(".")


@pytest.mark.parametrize("rows", [[{"point": "a", "cost_sl": 0.01}, {"point": "b, c", "cost_sl": 2.5}]])
def test_the_csv_table_reads_back(tmp_path, rows):
    tt.write_csv(rows, tmp_path / "t.csv")
    with open(tmp_path / "t.csv", newline="", encoding="utf-8") as fh:
        back = list(csv.DictReader(fh))
    assert back == [{k: str(v) for k, v in row.items()} for row in rows]
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
