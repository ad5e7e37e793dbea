"""`MotorFaults`: the injected faults of `sim.virtual.devices.motors.SimMotorBus` and the health
they leave behind.

A move draws the scene's ``faults:`` rules (`sim.virtual.faults`) for its sample: an
``overheat`` or a ``supply_sag`` takes effect at once, for the rule's time on the clock;
any other fault is armed and strikes during the move (the bus decides when). A struck
motor fault latches its axis's flags until a reboot; an overheating one stays latched
while the axis is hot, and an injected ``shift_deg`` jumps its encoder at the reboot.
"""

from __future__ import annotations

import math

from drivers.errors import CommError, DriverError, MotorFault
from drivers.values import Health
from gonio.scene import MOTOR_KINDS, FaultRule
from sim.virtual.faults import FaultInjector

#: Temperature (°C) and supply voltage (V) of a healthy simulated motor.
NOMINAL_TEMPERATURE_C = 35.0
NOMINAL_VOLTAGE_V = 12.0


class MotorFaults:
    """Fault and health state of the axes ``names`` (motor ids ``motor_ids``).

    Attributes
    ----------
    pending : FaultRule or None
        The fault armed for the present move, until it strikes or the axes are held.
    latched : dict
        Faulted axes and their hardware-error flags.
    overheat : tuple or None
        An injected overheat: (axis, °C, until when on the clock, s).
    supply_sag : tuple or None
        An injected supply sag: (V, until when on the clock, s).
    """

    def __init__(
        self, injector: FaultInjector, names: tuple[str, ...], motor_ids: dict[str, int]
    ) -> None:
        self.injector = injector
        self.names = names
        self.motor_ids = motor_ids
        self.pending: FaultRule | None = None
        self.latched: dict[str, tuple[str, ...]] = {}
        self.overheat: tuple[str, float, float] | None = None
        self.supply_sag: tuple[float, float] | None = None
        self._shift: dict[str, float] = {}  # how far an axis's encoder jumps at its reboot

    def arm(self, sample: int, move: int, t0: float) -> None:
        """Draw the faults of move ``move`` of ``sample`` started at ``t0`` (s): an
        overheat or a supply sag takes effect now, another fault is armed (`pending`)."""
        rule = self.injector.fired(sample, move, MOTOR_KINDS) if self.injector else None
        self.pending = rule
        if rule is not None and rule.kind == "overheat":
            self.pending = None
            self.overheat = (rule.axis or self.names[0], rule.temperature_c, t0 + rule.for_s)
        elif rule is not None and rule.kind == "supply_sag":
            self.pending = None
            self.supply_sag = (rule.voltage_v, t0 + rule.for_s)

    def disarm(self) -> None:
        """Forget the armed fault (the axes are held)."""
        self.pending = None

    def strike(self, rule: FaultRule, sample: int, now: float) -> DriverError:
        """The error of the injected motor fault ``rule`` striking at ``now`` (s) in a
        move of ``sample``; a motor fault latches its axis's flags (and heat)."""
        if rule.kind == "comm_error":
            what = "no status packet" if rule.packet == "lost" else "a corrupt status packet (CRC)"
            return CommError(
                f"{what} from the bus during the move into sample {sample} "
                "(injected); every axis told to hold",
                port="simulated",
            )
        axis = rule.axis or self.names[0]
        self.latched[axis] = rule.flags
        if rule.shift_deg:
            self._shift[axis] = math.radians(rule.shift_deg)
        if "overheating" in rule.flags:  # hot from now on, for the rule's time
            self.overheat = (axis, rule.temperature_c, now + rule.for_s)
        return self.fault_error(axis, rule.flags)

    def fault_error(self, axis: str, flags: tuple[str, ...]) -> MotorFault:
        """The `MotorFault` of ``axis`` reporting ``flags``."""
        motor_id = self.motor_ids[axis]
        return MotorFault(
            f"motor {motor_id} (axis {axis!r}) reports a hardware error: {', '.join(flags)}",
            motor_id=motor_id,
            axis=axis,
            flags=flags,
        )

    def check_clear(self) -> None:
        """`MotorFault` of the first latched axis, if any."""
        if self.latched:
            raise self.fault_error(*next(iter(self.latched.items())))

    def hot_now(self, now: float) -> tuple[str, float, float] | None:
        """The injected overheat still in force at ``now`` (s), or None."""
        hot = self.overheat
        return hot if hot is not None and now < hot[2] else None

    def health(self, now: float) -> dict[str, Health]:
        """Each axis's health at ``now`` (s): an overheat's axis at its temperature until
        it has cooled, a sag's voltage while it lasts, the latched flags; no load."""
        hot = self.hot_now(now)
        sag = self.supply_sag
        volts = sag[0] if sag is not None and now < sag[1] else NOMINAL_VOLTAGE_V
        return {
            n: Health(
                temperature_c=hot[1] if hot is not None and hot[0] == n else NOMINAL_TEMPERATURE_C,
                voltage_v=volts,
                error_flags=self.latched.get(n, ()),
            )
            for n in self.names
        }

    def clear(self, axis: str) -> None:
        """Clear ``axis``'s latched fault (a reboot); its encoder shift stays pending."""
        self.latched.pop(axis, None)

    def recover(self, axis: str, now: float) -> float:
        """Reboot ``axis`` at ``now`` (s): `MotorFault` again if its latched fault is an
        overheating one and it is still hot, else the fault clears; how far (rad) its
        encoder jumps (0 without an injected ``shift_deg``)."""
        flags = self.latched.get(axis, ())
        hot = self.hot_now(now)
        if "overheating" in flags and hot is not None and hot[0] == axis:
            raise self.fault_error(axis, flags)
        self.latched.pop(axis, None)
        return self._shift.pop(axis, 0.0)
