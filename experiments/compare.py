"""Fig. 4 a-g overlays (reference / single / split / best) and the speed comparison, measured side by side.

    python experiments/compare.py

The study is fluidfilm.studies.compare; config conf/compare.yaml.
"""
from fluidfilm.studies import compare
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(compare, "the model comparison")
