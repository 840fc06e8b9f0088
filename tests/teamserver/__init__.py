"""Tests of the team server (teamserver/), a package per sub-package."""
