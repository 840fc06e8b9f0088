"""Production: orders made into products, their tasks and their books.

:mod:`.manager` wires the collaborators together and runs a planning round;
each of the other modules is one concern of production (products and
tasks, station locks, the planning world, caps, slides, the storage shelf
and the store-or-hand-over choice, clean-up products, repair, task
outcomes, station health, feeds the stations must confirm).  See
``docs/architecture.md``."""
