"""Tests of teamserver.planning."""
