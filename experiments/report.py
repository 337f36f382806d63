"""reports/metrics.json and reports/paper_comparison.md: our numbers beside the paper's.

    python experiments/report.py

The study is fluidfilm.studies.report (the report itself: fluidfilm.reporting.report); config conf/report.yaml.
"""
from fluidfilm.studies import report
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(report, "the report")
