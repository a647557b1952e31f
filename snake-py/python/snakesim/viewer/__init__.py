"""Looking at runs and agents: Rerun recordings (:mod:`~snakesim.viewer.recording`), the Rerun viewer
processes (:mod:`~snakesim.viewer.processes`), replay figures and animations
(:mod:`~snakesim.viewer.replay`) and learning curves (:mod:`~snakesim.viewer.plots`). Importing this
package imports none of them."""
