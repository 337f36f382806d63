"""The workflow layer: Hydra entry points, config schemas and checks, sweeps, MLflow tracking, the DVC pipeline."""
