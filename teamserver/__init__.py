"""The team server: the high layer between the refbox and the robots.

Sub-packages, each importing only those below it (see docs/architecture.md):
:mod:`.knowledge` (records, fused beliefs, the SQLite-backed knowledge base),
:mod:`.links` (refbox, robots, the task link), :mod:`.planning` (HTN
production planning), :mod:`.production` (products and their books),
:mod:`.dispatch` (tasks to robots), :mod:`.exploration` (where the machines
are).  :mod:`.server` composes them into :class:`~teamserver.server.TeamServer`;
:mod:`.cli`, :mod:`.game` and :mod:`.status` are its entry points."""
