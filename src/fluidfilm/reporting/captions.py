"""The caption of every figure the pipeline draws, written once: ``CAPTIONS`` (path under ``reports/`` -> caption).

The results page (``reporting.readme``) shows each figure with its caption; the figure tests check that every
figure the studies draw has one.
"""
from __future__ import annotations

# path of the PNG under reports/ -> the caption the results page shows under it
CAPTIONS: dict[str, str] = {
    "figures/fig2_grid.png": (
        "Fig. 2: film reaction |F| of the journal at rest against the eccentricity ratio ε for the paper's "
        "coarse and dense grids, and their error against the grid-converged (Richardson) reference. Grey band: "
        "ε > 0.9, where the paper switches to the dense grid."),
    "figures/fig3_velocity.png": (
        "Fig. 3: film reaction components F1, F2 against the journal's velocity along the line of centres "
        "(radial, squeeze) and across it (tangential), one curve per eccentricity; symmetric-log force axis."),
    "figures/fig4_reference.png": (
        "Fig. 4, reference model: journal-centre orbits of the seven cases in units of the clearance c "
        "(grey circle: ε = 1; gravity down the page); thin: transient, thick: settled orbit."),
    "figures/fig4_comparison.png": (
        "Fig. 4, surrogates against the reference: the same orbits for the single, split and best surrogates "
        "drawn on the reference's wide grey band; a coloured line inside the band means agreement."),
    "figures/equilibrium_locus_reference.png": (
        "Static equilibria of the reference model for growing load: the journal-centre locus in units of c "
        "(left) and the eccentricity ratio ε and attitude angle against the Sommerfeld number S (right)."),
    "figures/ensemble.png": (
        "Seeds of the best surrogate, their ensemble and the hybrid with the reference: orbit distance from the "
        "reference per Fig. 4 case (left, log scale; dashed: the 2 % of c criterion) and the share of force "
        "evaluations flagged (right)."),
    "figures/error_map.png": (
        "Where the best surrogate's force errors sit: 99th-percentile relative force error per (ε, |V|) bin "
        "for held-out random states and for states along the reference orbits; n: states in the bin."),
    "figures/universal_error_map.png": (
        "The universal plain-bearing surrogate on bearings it never saw: 99th-percentile relative force error "
        "per held-out L/D and eccentricity bin, random sizes, clearances, speeds and viscosities, for each "
        "cavitation rule, against the grid-converged reference."),
    "figures/universal_kc.png": (
        "The universal surrogate's stiffness and damping along the equilibrium locus of the held-out L/D values: "
        "largest relative error of the direct and cross terms against the grid-converged reference, per "
        "eccentricity; lines at the 2 % and 5 % goals."),
    "grading_study/figure.png": (
        "Grading study: held-out and orbit force errors of each dataset grading against the dataset size and "
        "the time the reference model took to make it; labels: the swept values, (n/7): Fig. 4 cases within "
        "2 % of c."),
    "ablation/figure.png": (
        "Ablation of input scaling and eccentricity split at one dataset: held-out and orbit force errors per "
        "job; (n/7): Fig. 4 cases within 2 % of c."),
    "figures/fig5_a_dqn.png": (
        "Fig. 5a: rotor orbit under a growing imbalance with the DQN agent moving the conical sleeve; colour: "
        "time; grey circles: the clearance of each sleeve position used (dashed: nominal)."),
    "figures/fig5_b_none.png": "Fig. 5b: the same imbalance ramp without control (sleeve fixed at the nominal clearance).",
    "figures/fig5_c_mpc.png": "Fig. 5c: the same imbalance ramp under model predictive control of the sleeve.",
    "figures/fig5_amplitude.png": (
        "Fig. 5: orbit amplitude (top) and sleeve position (bottom) against time for the three controllers "
        "along the imbalance ramp."),
    "figures/characteristics_static.png": (
        "Static characteristics of the paper's bearing against the Sommerfeld number S, for two cavitation "
        "rules and two feed assumptions: eccentricity ratio, attitude angle, power loss and side flow."),
    "figures/characteristics_coefficients.png": (
        "Dimensionless stiffness K c/W and damping C c ω/W along the equilibrium locus for the reference "
        "models and the surrogates; the axes span the reference's values, surrogate values beyond them are "
        "marked at the axis edge with the extreme value written."),
    "figures/characteristics_stability_map.png": (
        "Stability map (Lund's criterion, rigid rotor): the critical dimensionless mass m̄ c ω²/W above which "
        "the rotor whirls (left; dashed: the paper's rotor as its speed varies; triangles: nonlinear "
        "trajectories just below and above the threshold) and the whirl frequency ratio at onset (right). "
        "Values of a surrogate beyond the axes are marked at the edge with their value."),
    "figures/paper_scale.png": (
        "The paper's networks (1x50 tanh, min-max map, Levenberg-Marquardt, validation stop) against the number "
        "of samples they are trained on: the equilibrium offset under the rotor's weight (left) and the median "
        "orbit RMS error over cases a-g (right), in % of the clearance, single and split; the recipe's variants "
        "at one size beside them."),
    "figures/paper_scale_curve.png": (
        "The paper's networks against data size, every size on record: the pipeline's 40,000 samples and the "
        "committed runs beyond it (160,000 to 2,560,000 samples: make paper-scale-curve; all 4,512,900: make "
        "paper-full-scale). Filled: trained to the validation rule; hollow: stopped by a Levenberg-Marquardt time "
        "budget, not converged. Dashed: the 2 %-of-c rule."),
    "figures/runup_cascade.png": (
        "Run-up and run-down of the paper's rotor through its oil-whirl threshold (reference model): the full "
        "spectrum of the journal's orbit in windows of 16 revolutions, each drawn at the height of its shaft speed "
        "(a cascade or waterfall; line height: log amplitude); forward whirl at positive orders, the imbalance "
        "response at -1x, the whirl near 0.5x; dashed: Lund's linear threshold."),
    "figures/runup_amplitude.png": (
        "Sub-synchronous amplitude (top, log scale) and whirl frequency ratio (bottom) against shaft speed on the "
        "run-up (solid) and run-down (dashed), per force model; dotted: the onset from each transient, dashed: "
        "Lund's linear threshold, star: Lund's whirl ratio there. The gap between the curves is the hysteresis."),
    "figures/online_assessment.png": (
        "On-line assessment from two probes (stage online_assessment), one column per scenario (a load step, a "
        "warm-up, a blade loss, a misalignment the model lacks): the EKF's static load, imbalance and viscosity "
        "against time with their 2-sigma bands, the offline RTS smoother, the reference plant's true values and "
        "the centreline baseline's load; bottom: the innovation test and where the mismatch flag fires."),
    "figures/cavitation_rules_orbits.png": (
        "The paper's seven cases (Fig. 4 a-g) under three cavitation rules on one grid, one feed (a groove at "
        "the top) and one solver: settled orbits in units of c, gravity down the page; black: the mass-conserving "
        "(JFO / Elrod-Adams) film, dashed: Guembel and Swift-Stieber."),
    "figures/cavitation_rules_runup.png": (
        "Left: Pfeil's run-up (d = L = 0.1 m, c = 150 um, 200 kg, 60 -> 140 Hz in 1 s) under the three rules: "
        "sub-synchronous amplitude against shaft speed, dotted: each onset. Right: the paper's bearing as a "
        "squeeze-film damper (circular orbit at eps 0.5, 100 Hz, no rotation, fed at 20 kPa): radial (solid) and tangential "
        "(dashed) film force over a whirl period."),
    "figures/jfo_surrogate_orbits.png": (
        "The JFO film's force surrogate with memory (the journal's path over the last 40 ms as input) against "
        "its reference on the paper's seven cases: settled orbits in units of c, gravity down the page; black: "
        "the mass-conserving film, red dashes: the surrogate."),
}
