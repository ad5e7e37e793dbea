"""Watching a run live: the read model of a run file as it grows (`gonio.live.model`)
and what is shown of it (`gonio.live.views`), shared by the local web page
(`gonio.live.server`, ``gonio serve``) and the terminal view (`gonio.live.terminal`,
``gonio watch``)."""
