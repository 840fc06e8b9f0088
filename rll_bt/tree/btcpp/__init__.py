"""Trees to and from BehaviorTree.CPP v4 XML, for Groot2.

    from rll_bt.tree.btcpp import export_xml, import_xml, nodes_model, problems
    xml = export_xml(["trees/deliver.yaml"], search_path=["trees"])  # the tree and its subtrees
    assert problems(xml) == []                   # what BT.CPP 4's parser checks
    files = import_xml(xml)                      # {"deliver.yaml": "...", "common/deliver_held.yaml": ...}
    catalogue = nodes_model()                    # every node type as a <TreeNodesModel>

``rll-bt tree export --format btcpp`` and ``rll-bt tree import`` are the
command-line side.  :mod:`.mapping` says what each construct becomes.
"""
from .mapping import FORMAT
from .reader import import_xml, write_trees
from .verify import problems
from .writer import ExportError, export_xml, nodes_model

__all__ = ["FORMAT", "ExportError", "export_xml", "import_xml", "nodes_model", "problems", "write_trees"]
