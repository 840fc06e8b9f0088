"""Tests of teamserver.exploration."""
