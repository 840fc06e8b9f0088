"""Short whole games for the game tests: SETUP 1 s, 40 s of exploration with
the oracle strategy (robots go straight to the stations), a short production,
a team server that drops a robot after 3 s without a heartbeat."""
from __future__ import annotations

from games import GameOptions, LockstepGame
from teamserver.dispatch import DispatchConfig
from teamserver.links.agents import from_wire

PRODUCTION_KINDS = ("get_workpiece", "put_workpiece", "retrieve_cap", "mount_ring", "mount_cap",
                    "deliver", "discard")


def short_game(seed: int = 3, **kw) -> LockstepGame:
    opts = {"seed": seed, "setup": 1.0, "exploration": 40.0, "production": 300.0, "strategy": "oracle",
                "extra": {"dispatch": DispatchConfig(heartbeat_timeout=3.0)}}
    opts.update(kw)
    return LockstepGame(GameOptions(**opts))


def in_production(game) -> bool:
    st = game.refbox.status()
    return st.phase == "PRODUCTION" and st.state == "RUNNING"


def tasks(game) -> dict[int, dict]:
    return {t["id"]: t for t in game.teamserver.snapshot()["tasks"]}


def running(game, kinds=PRODUCTION_KINDS) -> dict[int, tuple[str, int]]:
    """Robot number -> (kind, task id) of the production trees running now (the team
    server's task id: an agent runs an assignment's wire id, :func:`from_wire`)."""
    out = {}
    for n, agent in game.agents.items():
        run = agent.run
        if run is not None and not run.done and run.kind in kinds:
            out[n] = (run.kind, from_wire(run.task_id)[0])
    return out
