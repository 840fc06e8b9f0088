"""Faults in a whole lockstep game: the refbox, the PyBullet world, the team
server and three real agents with their task trees."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from game_testkit import in_production, running, short_game, tasks  # noqa: E402

from rll_bt.game.msglog import MessageLog  # noqa: E402


def test_a_killed_agent_loses_its_task_the_game_goes_on_and_it_rejoins_with_the_map():
    with short_game() as game:
        def fetching(g):
            if not in_production(g):
                return False
            return any(kind in ("get_workpiece", "retrieve_cap") and g.sim.backend("CYAN", n).holding() is False
                       for n, (kind, _) in running(g).items())
        assert game.run_until(fetching, limit=120.0), "no robot went to fetch anything"
        victim, (kind, tid) = next((n, r) for n, r in running(game).items()
                                   if r[0] in ("get_workpiece", "retrieve_cap"))
        game.kill_agent(victim)

        def taken_back(g):
            snap = g.teamserver.snapshot()
            return snap["robots"][victim]["status"] == "LOST" and tasks(g)[tid]["robot"] != victim
        assert game.run_until(taken_back, limit=15.0), "the dead robot kept its task"
        # the very step goes to another robot (or back to the pool until one is free)
        t = tasks(game)[tid]
        assert t["state"] in ("PENDING", "ASSIGNED", "DONE") and t["robot"] != victim

        points = game.sim.status().points["CYAN"]
        game.run_for(10.0)
        st = game.sim.status()
        assert st.phase == "PRODUCTION" and st.state == "RUNNING"
        assert st.points["CYAN"] >= points
        assert running(game), "the other robots stopped working"

        agent = game.start_agent(victim)
        assert game.run_until(lambda g: g.teamserver.snapshot()["robots"][victim]["status"] == "ACTIVE"
                              and agent.map_updates > 0, limit=10.0)
        known = game.teamserver.snapshot()["known"]
        truth = {n: s.zone for n, s in game.sim.stations().items()}
        mm = agent.services["machine_map"]
        assert known and all(mm[name].zone == truth[name] for name in known)


def test_a_restarted_team_server_resumes_from_its_database_and_goes_on_playing():
    with short_game(seed=4) as game:
        def something_done(g):
            return in_production(g) and any(t["state"] == "DONE" and t["kind"] != "explore_zone"
                                             for t in tasks(g).values())
        assert game.run_until(something_done, limit=150.0)
        before = tasks(game)
        game.restart_teamserver()
        restarted = game.clock.now()
        snap = game.teamserver.snapshot()
        assert snap["restarts"] == 1 and snap["color"] == "CYAN"
        assert set(before) <= {t["id"] for t in snap["tasks"]}         # the plan survived
        assert all(snap["robots"][n]["status"] == "ACTIVE" for n in (1, 2, 3))

        def resumed(g):     # results of the robots reach the new server, and it hands out work
            ts = tasks(g).values()
            return (any((t["finished_at"] or 0) > restarted for t in ts)
                    and any((t["assigned_at"] or 0) > restarted for t in ts))
        assert game.run_until(resumed, limit=60.0), "the new server neither heard results nor gave tasks"
        assert game.sim.status().phase == "PRODUCTION"


def test_a_station_going_down_gets_no_work_until_it_is_back(tmp_path):
    with short_game(seed=5) as game:
        log = MessageLog(tmp_path / "m.jsonl", game.clock, {"teamserver": game.team_reg}, game.ref_reg,
                         key=game.options.key)
        prepares = []
        game.bus.tap(lambda ch, src, frame: _prepare(log, ch, frame, game.clock.now(), prepares))

        def planned(g):
            return in_production(g) and any(t["state"] == "PENDING" and t["machine"] == "C-BS"
                                            for t in tasks(g).values())
        assert game.run_until(planned, limit=120.0)
        down_at = game.clock.now()
        game.station_down("C-BS", 30.0)
        game.run_for(1.0)
        assert game.teamserver.snapshot()["stations"]["C-BS"] == "DOWN"
        game.run_for(25.0)
        during = [t for t in tasks(game).values() if t["machine"] == "C-BS" and t["assigned_at"] is not None
                  and down_at + 1.0 < t["assigned_at"] < down_at + 26.0]
        assert not during, f"tasks sent to C-BS while it was down: {during}"
        assert not [t for t in prepares if t[1] == "C-BS" and down_at + 1.0 < t[0] < down_at + 26.0]
        assert any(t["assigned_at"] and t["assigned_at"] > down_at for t in tasks(game).values()
                   if t["machine"] != "C-BS"), "nothing else was done meanwhile"
        # back up: the plan goes on at the base station (its robot may have waited there)
        assert game.run_until(lambda g: any(m == "C-BS" and t > down_at + 30.0 for t, m in prepares),
                              limit=40.0), "C-BS was not used again after its down period"
        log.close()


def _prepare(log, channel, frame, now, out):
    msg, _ = log.decode(channel, frame)
    if msg is not None and msg.DESCRIPTOR.name == "PrepareMachine":
        out.append((now, msg.machine))
