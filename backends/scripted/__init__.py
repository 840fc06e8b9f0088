"""A scripted test backend: replays readings from a script and records commands.

For running trees without a simulator (``rll-bt tree run FILE --backend
scripted --backend-opt script=robot.yaml``) and for tests.
"""
from .backend import ScriptedBackend, load_script

__all__ = ["ScriptedBackend", "load_script"]
