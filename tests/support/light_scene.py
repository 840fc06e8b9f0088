"""A frame of the project's renderer showing a whole signal tower, for the light readers' tests."""
import numpy as np

from skills.perception.light.scenes import SceneRenderer, world_factory


def rendered_tower(red: bool = True, yellow: bool = False, green: bool = True, seed: int = 11,
                   min_height: int = 50):
    """(BGR image, tower box) of a random view (seeded) of a 2016 world whose stations all show
    the given lights, with a whole tower at least ``min_height`` pixels high."""
    world = world_factory()("rcll2016", seed=2)
    try:
        r = SceneRenderer(world, np.random.default_rng(seed))
        lights = {"red": "ON" if red else "OFF", "yellow": "ON" if yellow else "OFF",
                  "green": "ON" if green else "OFF"}
        for name in world.machines:
            world.set_lights(name, **lights)
            world.station(name).show_lights(world.cid, world.time, world.blink_hz)
        state = int(green) + 2 * int(yellow) + 4 * int(red)
        for _ in range(40):
            r.randomise_look()
            view = r.tower_view()
            if view is None:
                continue
            f = r.render(*view, dict.fromkeys(world.machines, state))
            for t in f.towers:
                if t.clean and t.box[3] >= min_height:
                    return f.image, t.box
        raise AssertionError(f"no view of a whole tower {min_height} px high in 40 tries")
    finally:
        world.close()
