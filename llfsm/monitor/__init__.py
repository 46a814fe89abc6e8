"""Properties judged on a run and on a recorded bag (SPEC 16; docs/monitor.md).

- `judge`: the verdicts of each kind over a sequence of ringlet boundaries (llfsm.props's
  language and table of kinds), shared by the run's monitor and `llfsm bag check`;
- `run`: `llfsm run --monitor` / `--monitor-property`: the monitor on a live arrangement,
  judging only where a property's value can change, through `reads` (what each ringlet of a
  compiled machine can change, from its module's text) and `variant` (a machine's ringlets with
  the checks compiled in); watching every boundary, through the scheduler's watcher, only when
  something else calls for it;
- `topic`: the verdicts as messages on `/llfsm/monitor` (llfsm_msgs/msg/MonitorEvent);
- `bag`: `llfsm bag check BAG`, the same properties over a bag's `/llfsm/M/state` and published
  topics.
"""

from .judge import MonitorError, Verdict, property_source
from .run import ON_VIOLATION, Monitor

__all__ = ["ON_VIOLATION", "Monitor", "MonitorError", "Verdict", "property_source"]
