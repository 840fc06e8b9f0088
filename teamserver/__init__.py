"""The team server: knowledge base, exploration, HTN planning, dispatch."""
