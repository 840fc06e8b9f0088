"""Device drivers a real robot's backend composes, and emulators that speak
their protocols: lasers (:mod:`.laser`: Hokuyo URG over SCIP 2.0, SICK TiM5xx
over CoLa), the camera (:mod:`.camera`), and :mod:`.ptyrunner` to put a
device model behind a pseudo-terminal."""
