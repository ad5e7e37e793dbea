"""Watching a run live: the read model of a run file as it grows (`gonio.live.model`,
over `gonio.store.follow`), what is shown of it (`gonio.live.views`) and what the server
derives from its samples every few of them (`gonio.live.derived`: a fit's residuals, the
reconstruction's slice), shared by the local web page (`gonio.live.server`,
``gonio serve``) and the terminal view (`gonio.live.terminal`, ``gonio watch``)."""

from typing import TYPE_CHECKING

from gonio.faces import lazy_face

if TYPE_CHECKING:  # the names for the type checker (`as`: re-exported)
    from gonio.live import derived as derived
    from gonio.live import listen as listen
    from gonio.live import server as server
    from gonio.live.model import LiveRun as LiveRun
    from gonio.live.terminal import line as line
    from gonio.live.terminal import screen as screen
    from gonio.live.views import overview as overview
    from gonio.live.views import values as values

#: The names of the face that load with their module when first used
#: (`gonio.faces`), by module.
WHERE = {
    "LiveRun": "model",
    "derived": "derived",
    "line": "terminal",
    "listen": "listen",
    "overview": "views",
    "screen": "terminal",
    "server": "server",
    "values": "views",
}

__all__ = list(WHERE)
if not TYPE_CHECKING:
    __getattr__, __dir__ = lazy_face(__name__, WHERE)
