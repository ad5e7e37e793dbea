"""``--format bluesky``: a run as event-model documents (the bluesky data model), one
``[name, document]`` JSON array per line (docs/reference/formats.md#bluesky).

Documents, in order: ``start`` (the run's metadata: plan, rig and scene texts, hashes,
backend, seed, versions, sessions), the ``primary`` stream's ``descriptor`` (one data
key per `gonio.export.columns` column, with its unit), one ``event`` per sample, the
``journal`` stream's descriptor and one event per journal event (kind, target, run time,
data as JSON text), and ``stop`` (``success`` when the run completed, ``fail`` after a
fault, else ``abort`` with the last session's outcome as the reason). The documents are
composed and validated by event-model (`event_model.compose_run`). Identifiers are
UUIDs derived from the run's content hash and creation time, so exporting the same run
twice gives the same file. JSON has no NaN: a value the run does not have is ``null``.
"""

from __future__ import annotations

import json
import uuid
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from gonio.errors import GonioError
from gonio.export.columns import Column, sample_columns
from gonio.export.steps import step
from gonio.output import PendingOutput
from gonio.store import Run

if TYPE_CHECKING:
    from gonio.export import Options

_DTYPES = {"b": "boolean", "i": "integer", "f": "number", "U": "string"}


def _event_model() -> Any:
    try:
        import event_model  # optional: the bluesky extra
    except ImportError:
        raise GonioError(
            "--format bluesky needs event-model: pip install 'gonio[bluesky]'"
        ) from None
    return event_model


def _unix(utc: str | None, default: float) -> float:
    return default if not utc else datetime.fromisoformat(utc).timestamp()


def _json_values(values: np.ndarray) -> list[Any]:
    """Plain Python values, NaN as None."""
    if values.dtype.kind == "f":
        return [None if np.isnan(v) else v for v in values.tolist()]
    return list(values.tolist())


def data_key(column: Column, source: str) -> dict[str, Any]:
    """The event-model data key describing ``column``."""
    return {
        "dtype": _DTYPES[column.values.dtype.kind],
        "dtype_numpy": column.values.dtype.str,
        "shape": [],
        "source": source,
        "units": column.unit,
    }


def documents(run: Run) -> list[tuple[str, dict[str, Any]]]:
    """The run's documents, in order (see the module docstring)."""
    em = _event_model()
    meta = dict(run.meta)
    started = float(meta.get("started_unix") or _unix(meta.get("created_utc"), 0.0))
    namespace = uuid.uuid5(
        uuid.NAMESPACE_URL,
        f"gonio:{meta.get('hashes', {}).get('content')}:{meta.get('created_utc')}",
    )

    def uid(what: str) -> str:
        return str(uuid.uuid5(namespace, what))

    columns = sample_columns(run)
    metadata = {
        "gonio": {k: v for k, v in meta.items() if k not in ("started_unix",)},
        "plan_name": meta.get("plan_name"),
        "columns": {c.key: {"units": c.unit, "description": c.description} for c in columns},
        "sessions": [
            {
                "id": s.id,
                "started_utc": s.started_utc,
                "ended_utc": s.ended_utc,
                "outcome": s.outcome,
                "info": dict(s.info),
            }
            for s in run.sessions
        ],
    }
    bundle = em.compose_run(uid=uid("start"), time=started, metadata=metadata)
    docs: list[tuple[str, dict[str, Any]]] = [("start", dict(bundle.start_doc))]
    source = f"gonio:{run.path.name}"

    primary = bundle.compose_descriptor(
        name="primary",
        data_keys={c.key: data_key(c, source) for c in columns},
        uid=uid("descriptor:primary"),
        time=started,
    )
    docs.append(("descriptor", dict(primary.descriptor_doc)))
    values = [_json_values(c.values) for c in columns]
    utc = run.samples["utc"]
    for i in range(len(run)):
        t = _unix(str(utc[i]), started)
        data = {c.key: v[i] for c, v in zip(columns, values, strict=True)}
        event = primary.compose_event(
            data=data,
            timestamps=dict.fromkeys(data, t),
            seq_num=i + 1,
            uid=uid(f"event:primary:{i}"),
            time=t,
        )
        docs.append(("event", dict(event)))

    journal = bundle.compose_descriptor(
        name="journal",
        data_keys={
            "kind": {"dtype": "string", "shape": [], "source": source},
            "target": {"dtype": "integer", "shape": [], "source": source},
            "t": {"dtype": "number", "shape": [], "source": source, "units": "s"},
            "data": {"dtype": "string", "shape": [], "source": source},
        },
        uid=uid("descriptor:journal"),
        time=started,
    )
    docs.append(("descriptor", dict(journal.descriptor_doc)))
    for j, e in enumerate(run.events):
        t = _unix(e.utc, started)
        data = {
            "kind": e.kind,
            "target": -1 if e.target is None else e.target,
            "t": e.t_s,
            "data": json.dumps(dict(e.data), sort_keys=True),
        }
        event = journal.compose_event(
            data=data,
            timestamps=dict.fromkeys(data, t),
            seq_num=j + 1,
            uid=uid(f"event:journal:{j}"),
            time=t,
        )
        docs.append(("event", dict(event)))

    outcome = run.sessions[-1].outcome if run.sessions else None
    status = "success" if outcome == "completed" else "fail" if outcome == "fault" else "abort"
    ended = run.sessions[-1].ended_utc if run.sessions else None
    last = max(float(d["time"]) for _, d in docs)  # the stop comes after every document
    stop = bundle.compose_stop(
        exit_status=status,
        reason="" if status == "success" else f"last session: {outcome or 'did not end'}",
        uid=uid("stop"),
        time=max(_unix(ended, last), last),
    )
    docs.append(("stop", dict(stop)))
    return docs


def to_text(docs: list[tuple[str, dict[str, Any]]]) -> str:
    """JSON lines: one ``[name, document]`` per line (NaN refused: there is none)."""
    return "".join(json.dumps([name, doc], allow_nan=False) + "\n" for name, doc in docs)


def export_run(run: Run, out: PendingOutput, options: Options) -> str:
    with step(f"building the documents of {len(run):,} samples"):
        docs = documents(run)
    with step(f"writing {len(docs):,} documents"):
        out.write_bytes(to_text(docs).encode())
    events = sum(1 for name, _ in docs if name == "event")
    return f"wrote {len(docs)} documents ({events} events) to {out.path} (bluesky JSON lines)"
