"""Skills: the low layer of rll-bt, over the backend interface only.

Every skill is a non-blocking :class:`~skills.activity.Activity`
(``start()`` / ``poll()`` / ``cancel()`` on a clock) and a behaviour-tree
node (:mod:`skills.nodes`, registered through the ``rll_bt.nodes`` entry
point ``skills``).  What the skills of one robot share is a
:class:`~skills.context.SkillContext`::

    ctx = SkillContext.create(backend, clock, rules.profile("rcll2016"),
                              start=Pose2D(3.5, -0.5, math.pi / 2), localisation="cheap")
    ctx.machines.set("C-BS", Pose2D(5.0, 0.75, 0.0))      # a confirmed station
    grab = GrabFrom(ctx, place_for("C-BS", "OUTPUT")).start()
    while grab.poll() is Status.RUNNING:
        ...                                               # tick at ~10 Hz
    grab.error                                            # SkillError.GRAB_FAILED, ...

Packages and modules:

- :mod:`skills.maps`: the known map (walls, confirmed stations), grids, ray casting
- :mod:`skills.localisation`: AMCL-style Monte Carlo localisation, relocalise
- :mod:`skills.navigation`: costmap, Dijkstra planner, path follower,
  laser safety, goals (pose, zone, station side), ``Navigate``, short motions
- :mod:`skills.manipulation`: places, tag alignment, laser docking, gripper
  sequences with the holding check, ``ApproachStation``, ``GrabFrom``, ``PutOnto``
- :mod:`skills.exploration`: ``ExploreZone`` and ``SightingCollector``
- :mod:`skills.machines`: the perception interface (``MachineObservation``,
  ``MachineMap``, ``TagSource``)
- :mod:`skills.perception`: tag and light detection (its own owner)
- :mod:`skills.testing`: ``FlatWorld``, a 2D test double of the backend
- :mod:`skills.errors`: ``SkillError`` (names of the team protocol's ``ErrorCode``)
"""
