"""Backends implementing rll_bt.backend.Backend; see DESIGN.md."""
