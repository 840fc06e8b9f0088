"""The shipped JSON Schema of tree files (tree.schema.json)."""
