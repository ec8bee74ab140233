"""Type stubs of the rigidtouch package (python/rigidtouch/__init__.py). SI units; the unit is in
every name."""

from typing import Any, Callable, Optional, Union

import numpy

from ._rigidtouch import (
    ContactParams as ContactParams,
    Data as Data,
    DeviceParams as DeviceParams,
    LoadOptions as LoadOptions,
    Model as Model,
    OutputError as OutputError,
    RenderParams as RenderParams,
    SimulatedDevice as SimulatedDevice,
    analyze_logs as analyze_logs,
    contact_dtype as contact_dtype,
    joint_state as joint_state,
    kinetic_energy as kinetic_energy,
    load_model as load_model,
    make_data as make_data,
    reset_data as reset_data,
    run as run,
    simulate_cohort as simulate_cohort,
    tick as tick,
    trace_dtype as trace_dtype,
)

def configure(model: Model, *, contact: Union[ContactParams, dict[str, Any], None] = None,
              render: Union[RenderParams, dict[str, Any], None] = None,
              device: Union[DeviceParams, dict[str, Any], None] = None) -> None: ...
def tap_args(**params: Any) -> list[str]: ...

class TapResult:
    metrics: dict[str, Any]
    trace: numpy.ndarray
    def __init__(self, metrics: dict[str, Any], trace: numpy.ndarray) -> None: ...
    @property
    def taps(self) -> list[dict[str, Any]]: ...
    def frame(self) -> Any: ...
    def taps_frame(self) -> Any: ...

def tap(*, check_finite: bool = True, **params: Any) -> TapResult: ...
def prepare_tap(**params: Any) -> tuple[Model, SimulatedDevice, dict[str, Any]]: ...
def sweep(spec: Union[str, dict[str, Any]], out: str, *, scheduler: Optional[str] = None,
          workers: Optional[int] = None,
          progress: Optional[Callable[[int, int], None]] = None) -> dict[str, Any]: ...

def fit_material(taps: list[dict[str, Any]], *, name: str = "fitted", device: str = "touch",
                 rate_hz: float = 1000.0, effective_mass_kg: float = 0.0) -> dict[str, Any]: ...
