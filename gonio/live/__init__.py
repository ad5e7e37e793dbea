"""Watching a run live: the read model of a run file as it grows (`gonio.live.model`,
over `gonio.store.follow`), what is shown of it (`gonio.live.views`) and what the server
derives from its samples every few of them (`gonio.live.derived`: a fit's residuals, the
reconstruction's slice), shared by the local web page (`gonio.live.server`,
``gonio serve``) and the terminal view (`gonio.live.terminal`, ``gonio watch``)."""
