"""Tests of teamserver.knowledge."""
