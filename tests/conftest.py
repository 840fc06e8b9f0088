"""Test-session set-up shared by every test."""
import rll_bt  # noqa: F401  (first: pins OpenBLAS's kernel before any test module loads numpy)
