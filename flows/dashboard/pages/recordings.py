"""A scenario as a Rerun recording: ``/scenarios/<run_id>/<seq_id>/<edit_id>/recording.rrd`` (made on request
by ``tasks.rerun_export``; 404 for an unknown scenario, 501 without the optional rerun-sdk package)."""

from __future__ import annotations

import logging

from fastapi import APIRouter, Request, Response
from fastapi.responses import JSONResponse

from flows.dashboard.rendering import state_of
from storage.errors import MissingInputError, UnsafePathError

logger = logging.getLogger(__name__)

router = APIRouter()

#: The media type of a Rerun recording.
RRD_MEDIA_TYPE = "application/vnd.rerun.rrd"


def recording_url(run_id: str, seq_id: str, edit_id: str) -> str:
    """The dashboard path of a scenario's recording (what a scenario card links as its download)."""
    return f"/scenarios/{run_id}/{seq_id}/{edit_id}/recording.rrd"


@router.get("/scenarios/{run_id}/{seq_id}/{edit_id}/recording.rrd", name="scenario_recording")
def recording(request: Request, run_id: str, seq_id: str, edit_id: str) -> Response:
    """The scenario's ``.rrd`` bytes, as a download named after it."""
    from tasks.rerun_export import RerunUnavailableError, scenario_recording  # the editing core: loaded on use

    try:
        data = scenario_recording(state_of(request).store, run_id, seq_id, edit_id)
    except RerunUnavailableError as exc:
        return JSONResponse({"error": str(exc)}, status_code=501)
    except (MissingInputError, FileNotFoundError, UnsafePathError, ValueError) as exc:
        logger.info("recording of %s/%s/%s: %s", run_id, seq_id, edit_id, exc)
        return JSONResponse({"error": f"no scenario {run_id}/{seq_id}/{edit_id}: {exc}"}, status_code=404)
    filename = f"{run_id}_{seq_id}_{edit_id}.rrd"
    return Response(data, media_type=RRD_MEDIA_TYPE,
                    headers={"Content-Disposition": f'attachment; filename="{filename}"'})
