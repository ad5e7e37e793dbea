"""`gonio serve` refuses what it must, with nothing changed in the run: control without
the run's token, with a wrong one, from another origin, over its rate; a run outside the
served folder; a request addressed to another host name; any API request without the
token on a non-loopback bind (which refuses to start without one). And what it serves:
the views of a run being acquired, decimated for a large run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from gonio.acquire import control
from gonio.cli import main
from gonio.errors import GonioError
from gonio.live import server
from gonio.store.read import open_run
from tests.gonio.live.conftest import ROOT, forked_acquire, free_port
from tests.support.acquire import MATTE, plan_file


def call(
    url: str, *, method: str = "GET", body: Any = None, headers: dict[str, str] | None = None
) -> tuple[int, dict[str, Any], dict[str, str]]:
    data = None if body is None else json.dumps(body).encode()
    hdrs = {"Content-Type": "application/json"} if body is not None else {}
    hdrs.update(headers or {})
    request = urllib.request.Request(url, data=data, method=method, headers=hdrs)
    try:
        with urllib.request.urlopen(request, timeout=10) as r:
            return r.status, _json(r.read()), dict(r.headers)
    except urllib.error.HTTPError as e:
        with e:
            return e.code, _json(e.read()), dict(e.headers)


def _json(text: bytes) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except ValueError:
        return {"text": text.decode(errors="replace")}
    assert isinstance(value, dict)
    return value


def _wait(check: Callable[[], bool], timeout_s: float = 30.0) -> None:
    give_up = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < give_up, "timed out"
        time.sleep(0.05)


def test_every_refusal_leaves_the_run_alone(
    tmp_path: Path, serve: Callable[[server.Served], Iterator[str]]
) -> None:
    folder = tmp_path / "served"
    folder.mkdir()
    plan = plan_file(tmp_path, target=100)
    path = folder / "run.sqlite"
    pid = forked_acquire(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path)], 0.04)
    try:
        _wait(lambda: path.exists() and len(open_run(path)) >= 3)
        token = control.read_token(path)
        assert token is not None
        outside = tmp_path / "outside.sqlite"
        outside.write_bytes(path.read_bytes())
        (folder / "link.sqlite").symlink_to(outside)
        with serve(server.Served(folder)) as base:
            ctl = f"{base}/api/control?run=run.sqlite"
            pause = {"action": "pause"}
            status, body, _ = call(ctl, method="POST", body=pause)
            assert status == 403 and "token" in body["error"]
            status, _, _ = call(ctl, method="POST", body=pause, headers={"X-Gonio-Token": "x" * 43})
            assert status == 403
            status, _, hdrs = call(
                ctl,
                method="POST",
                body=pause,
                headers={"X-Gonio-Token": token, "Origin": "http://evil.example"},
            )
            assert status == 403
            status, _, hdrs = call(ctl, method="OPTIONS", headers={"Origin": "http://evil.example"})
            assert status == 405
            assert not any(k.lower().startswith("access-control") for k in hdrs)
            form = urllib.request.Request(
                ctl,
                data=b"action=pause",
                method="POST",
                headers={"X-Gonio-Token": token, "Content-Type": "text/plain"},
            )
            with pytest.raises(urllib.error.HTTPError) as refused:
                urllib.request.urlopen(form, timeout=10)
            assert refused.value.code == 415
            refused.value.close()
            for name in ("../outside.sqlite", str(outside), "link.sqlite", "%2e%2e/outside.sqlite"):
                status, _, _ = call(f"{base}/api/overview?run={name}")
                assert status == 404, name
                status, _, _ = call(
                    f"{base}/api/control?run={name}",
                    method="POST",
                    body=pause,
                    headers={"X-Gonio-Token": token},
                )
                assert status == 404, name
            status, _, _ = call(f"{base}/api/runs", headers={"Host": "evil.example:80"})
            assert status == 403
            status, body, hdrs = call(f"{base}/api/overview?run=run.sqlite")
            assert status == 200 and body["state"] == "running"
            assert not any(k.lower().startswith("access-control") for k in hdrs)
            assert not any(k.lower() == "set-cookie" for k in hdrs)
            assert not control.requests_path(path).exists()  # nothing was posted
            # Within the rate: accepted (a resume while running is ignored); beyond: 429.
            resume, key = {"action": "resume"}, {"X-Gonio-Token": token}
            codes = [
                call(ctl, method="POST", body=resume, headers=key)[0]
                for _ in range(server.BURST + 1)
            ]
            assert codes == [202] * server.BURST + [429]
        _, status = os.waitpid(pid, 0)
        pid = 0
        assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
    finally:
        if pid:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
    run = open_run(path)
    assert run.complete
    assert not [e for e in run.events if e.kind in ("pause", "resume")]
    lines = control.requests_path(path).read_text().splitlines()
    assert len(lines) == server.BURST  # the accepted ones, each with who asked
    assert all("127.0.0.1 via gonio serve" in json.loads(x)["by"] for x in lines)


def test_control_of_a_run_not_being_acquired_is_refused(
    tmp_path: Path, serve: Callable[[server.Served], Iterator[str]]
) -> None:
    plan = plan_file(tmp_path, target=20)
    path = tmp_path / "done.sqlite"
    assert main(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path), "-q"]) == 0
    token = control.read_token(path)
    assert token is not None
    assert os.stat(control.token_path(path)).st_mode & 0o777 == 0o600
    with serve(server.Served(path)) as base:
        status, body, _ = call(
            f"{base}/api/control?run=done.sqlite",
            method="POST",
            body={"action": "stop"},
            headers={"X-Gonio-Token": token},
        )
        assert status == 409 and "not being acquired" in body["error"]
        status, body, _ = call(f"{base}/api/overview?run=done.sqlite")
        assert status == 200 and body["state"] == "completed" and body["measured"] == 20
        status, body, _ = call(f"{base}/api/points?run=done.sqlite")
        assert (
            status == 200
            and len(body["theta_o_deg"]) == len(body["phi_deg"]) == 20
            and body["unit"] == "sr⁻¹"
        )
        status, body, _ = call(f"{base}/api/runs")
        assert status == 200 and body["single"] and body["runs"][0]["name"] == "done.sqlite"
        status, _, _ = call(f"{base}/api/overview?run=other.sqlite")
        assert status == 404
    assert not control.requests_path(path).exists()


def test_a_non_loopback_bind_needs_a_token_for_every_request(
    tmp_path: Path,
    serve: Callable[[server.Served], Iterator[str]],
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(GonioError, match="needs a token"):
        server.Served(tmp_path, loopback=False)
    assert main(["serve", str(tmp_path), "--host", "0.0.0.0", "--port", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs a token" in err
    secret = "s" * 32
    with serve(server.Served(tmp_path, loopback=False, token=secret)) as base:
        assert call(f"{base}/api/runs")[0] == 401
        assert call(f"{base}/api/runs", headers={"X-Gonio-Token": "t" * 32})[0] == 401
        assert call(f"{base}/api/runs", headers={"X-Gonio-Token": secret})[0] == 200
        # Any host name reaches a server bound to every interface; the page holds no data.
        assert call(f"{base}/", headers={"Host": "lab-pc.example:8765"})[0] == 200
    token_file = tmp_path / "token"
    token_file.write_text(secret)
    os.chmod(token_file, 0o644)
    assert main(["serve", str(tmp_path), "--host", "0.0.0.0", "--token-file", str(token_file)]) == 2
    assert "chmod 600" in capsys.readouterr().err


def test_serve_refuses_a_missing_path(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["serve", str(tmp_path / "nothing")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    (tmp_path / "notes.txt").write_text("x")
    assert main(["serve", str(tmp_path / "notes.txt")]) == 2


def _children(pid: int) -> set[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.add(int(entry.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.slow
def test_serve_stopped_by_sigterm_leaves_no_worker(tmp_path: Path) -> None:
    plan = plan_file(tmp_path, target=30)
    path = tmp_path / "done.sqlite"
    assert main(["acquire", str(plan), "--scene", str(MATTE), "-o", str(path), "-q"]) == 0
    port = free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen(
        [sys.executable, "-m", "gonio", "serve", str(path), "--port", str(port),
         "--refit-every", "20"],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    workers: set[int] = set()
    try:
        assert child.stdout is not None and child.stdout.readline().startswith("serving")
        base = f"http://127.0.0.1:{port}"
        assert call(f"{base}/api/points?run=done.sqlite")[0] == 200  # the deriver starts
        _wait(lambda: bool(_children(child.pid)))
        workers = _children(child.pid)
        _wait(lambda: call(f"{base}/api/points?run=done.sqlite")[1]["fit"] is not None)
        child.send_signal(signal.SIGTERM)
        assert child.wait(30) in (0, -signal.SIGTERM)  # uvicorn ends as the signal asks
        _wait(lambda: not any(_alive(w) for w in workers), timeout_s=10)
    finally:
        for w in workers:  # first: a worker left behind holds the pipes open
            if _alive(w):
                os.kill(w, signal.SIGKILL)
        child.kill()
        child.communicate()
