"""Production planning: a small HTN engine (:mod:`.htn`), the RCLL production
domain (:mod:`.domain`), a schedule simulation for durations
(:mod:`.estimate`) and the choice of orders (:mod:`.planner`)."""
