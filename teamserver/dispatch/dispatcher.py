"""The dispatcher: ready tasks to robots, PrepareMachine at the right moment,
results, and robots that drop out.

:class:`Dispatcher` wires the collaborators of dispatch together, each
given the others it needs:

- :attr:`~Dispatcher.fleet` (:mod:`.fleet`): idle and available robots,
  assigning a task to a robot;
- :attr:`~Dispatcher.readiness` (:mod:`.readiness`): when a task may go;
- :attr:`~Dispatcher.holding` (:mod:`.holding`): robots left holding what
  they cannot use yet;
- :attr:`~Dispatcher.matcher` (:mod:`.matching`): ready tasks to robots;
- :attr:`~Dispatcher.preparer` (:mod:`.prepare`): PrepareMachine timing;
- :attr:`~Dispatcher.parking` (:mod:`.parking`): idle robots out of the
  stations' way;
- :attr:`~Dispatcher.results` (:mod:`.results`): task results, retries;
- :attr:`~Dispatcher.discards` (:mod:`.discards`): workpieces nothing
  needs;
- :attr:`~Dispatcher.dropouts` (:mod:`.dropouts`): silent robots, stations
  that went BROKEN or DOWN under a task.

The dispatcher sends nothing itself: it tells the task link
(:class:`~teamserver.links.tasks.TaskLink`) and the server flushes it at the
end of the tick.
"""
from __future__ import annotations

from ..knowledge.kb import KnowledgeBase
from ..links.tasks import TaskLink
from ..production.feeding import FeedMonitor
from ..production.manager import ProductionManager
from .config import DispatchConfig
from .discards import Discards
from .dropouts import Dropouts
from .fleet import Fleet
from .holding import Holding
from .matching import Matcher
from .parking import Parking
from .prepare import Preparer
from .readiness import Readiness
from .results import Results


class Dispatcher:
    """See the module doc.  ``production``: the production objects the dispatch
    works with; ``feeds``: the check that stations take what they are fed."""

    def __init__(self, kb: KnowledgeBase, production: ProductionManager, feeds: FeedMonitor,
                 clock, tasks: TaskLink, config: DispatchConfig | None = None):
        config = config if config is not None else DispatchConfig()
        self.kb = kb
        self.config = config
        self.feeds = feeds
        self.tasks = tasks
        pm = production
        self.fleet = Fleet(kb, clock, pm.locks, tasks)
        self.readiness = Readiness(kb, pm.locks, feeds, pm.slides, pm.caps, pm.buffers,
                                   pm.world, config, tasks=tasks, clock=clock)
        self.holding = Holding(kb, self.readiness, pm.locks, feeds, config)
        self.matcher = Matcher(kb, self.fleet, self.readiness, self.holding, pm.locks, pm.caps,
                               pm.slides, pm.world, config)
        self.preparer = Preparer(kb, clock, self.readiness, feeds, pm.world, tasks, config)
        self.parking = Parking(kb, clock, self.fleet, config)
        self.discards = Discards(kb, clock, self.fleet, pm.cleanup, config)
        self.results = Results(kb, clock, feeds=feeds, outcomes=pm.outcomes,
                               products=pm.products, repairs=pm.repairs, health=pm.health,
                               shelves=pm.cap_shelves, parking=self.parking, discards=self.discards, tasks=tasks,
                               config=config, fleet=self.fleet)
        self.dropouts = Dropouts(kb, clock, self.fleet, self.readiness, pm.products, tasks,
                                 config)
