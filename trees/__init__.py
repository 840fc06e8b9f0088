"""YAML behaviour trees, one per team-protocol task type."""
