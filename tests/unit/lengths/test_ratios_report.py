from handdb.lengths.ratios import joint_ratios, ratios_markdown, table1_measurements


def test_report_tabulates_the_cohort_and_states_both_discrepancies():
    report = ratios_markdown(joint_ratios(table1_measurements()))
    index_j1 = next(line for line in report.splitlines() if line.startswith("| index | J1 |"))
    assert "| 0.4846 | 0.4728 | 0.5047 | 0.0319 |" in index_j1
    assert "prints 0.4946" in report and "give 0.4846" in report
    assert "prints 169.97" in report and "give 169.67" in report
    assert report.count("| thumb |") == 2
