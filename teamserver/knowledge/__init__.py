"""What the team knows: the records (:mod:`.model`), observations fused into
beliefs (:mod:`.fusion`), the knowledge base over them (:mod:`.kb`) and its
SQLite store (:mod:`.store`).  Everything else in the team server reads and
writes through :class:`~teamserver.knowledge.kb.KnowledgeBase`."""
