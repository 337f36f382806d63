"""The paper's networks at larger scale, and the ingredient of their recipe that decides the verdicts.

    python experiments/paper_scale.py                                  # reports/paper_scale.json
    python experiments/paper_scale.py sizes=[640000,2560000] ablation.enabled=false out=...
    python experiments/paper_scale.py sizes=[] ablation.enabled=false full_scale.split.enabled=true

The curve: the paper's recipe (protocol ``paper``) at each of ``sizes``, single and split, one
seed; the mechanism: the split at ``ablation.n_samples`` with one ingredient changed at a time
(output map, frame, region boundaries, static rows near V = 0).  Every model: epochs, stop reasons,
training time, held-out errors per band, static force error along the equilibrium locus,
equilibrium offset, cases a-g by the 2 %-of-c rule and by the paper's reading.  Finished models and
the Levenberg-Marquardt checkpoints (after every epoch) stay under ``cache_dir``: the same command
resumes.  The study is fluidfilm.studies.paper_scale; config conf/paper_scale.yaml.
"""
from fluidfilm.studies import paper_scale
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(paper_scale, "the paper-scale study")
