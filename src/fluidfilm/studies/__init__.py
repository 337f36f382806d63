"""The studies behind the entry points in ``experiments/``: one module per study, ``run(cfg)`` and its checks."""
