"""Skills: py_trees behaviours and the algorithms behind them; see DESIGN.md."""
