"""The team server's links to the outside: the refbox (:mod:`.refbox_link`,
the public and team channels; :mod:`.refbox`, its messages into the
knowledge base and ours out) and the robots (:mod:`.agents`, the team
protocol; :mod:`.leases`, how long a robot may work unheard)."""
