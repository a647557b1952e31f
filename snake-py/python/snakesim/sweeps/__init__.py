"""Sweeps and searches on Ray: the plan and its folder (:mod:`~snakesim.sweeps.plan`), running a
sweep (:mod:`~snakesim.sweeps.sweep`), the Tune side (:mod:`~snakesim.sweeps.tune_runner`, needs the
``sweep`` extra), searches (:mod:`~snakesim.sweeps.search`) and the summary table
(:mod:`~snakesim.sweeps.summary`). Importing this package imports none of them."""
