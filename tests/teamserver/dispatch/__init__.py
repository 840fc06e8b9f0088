"""Tests of teamserver.dispatch."""
