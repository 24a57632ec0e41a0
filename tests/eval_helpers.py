"""Shared by the eval tests: its results compared across executions."""


def strip_timing(results):
    """Everything but the measured times, which no two executions share."""
    return {"config": results["config"],
            "results": [{k: v for k, v in r.items() if k != "frames_per_s"} for r in results["results"]]}
