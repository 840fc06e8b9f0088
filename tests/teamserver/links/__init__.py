"""Tests of teamserver.links."""
