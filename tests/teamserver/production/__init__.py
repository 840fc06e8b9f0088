"""Tests of teamserver.production."""
