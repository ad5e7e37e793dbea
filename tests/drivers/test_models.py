"""Each model's control table against its e-manual page, figure by figure.

The figures below are typed from the ROBOTIS e-manual's control tables
(emanual.robotis.com/docs/en/dxl/x/<model>/), not derived from the data under test.
"""

import pytest

from drivers.dynamixel.control_table import Area
from drivers.dynamixel.models import MODEL_NAMES, MODELS, model, model_number

# model: (number, Current Limit default/top or None, Velocity Limit default/top,
#         Min Voltage Limit default, (low, high) of the voltage limits, Temperature Limit,
#         last address of the table)
EMANUAL = {
    "XM430-W350": (1020, 1193, (200, 1023), 95, (60, 160), 80, 661),
    "XM430-W210": (1030, 1193, (330, 1023), 95, (95, 160), 80, 661),
    "XH430-W350": (1000, 648, (130, 1023), 95, (95, 160), 80, 661),
    "XH430-W210": (1010, 648, (210, 1023), 95, (95, 160), 80, 661),
    "XM540-W270": (1120, 2047, (128, 1023), 95, (95, 160), 80, 661),
    "XM540-W150": (1130, 2047, (230, 1023), 95, (95, 160), 80, 661),
    "XL430-W250": (1060, None, (265, 1023), 60, (60, 140), 72, 661),
    "2XL430-W250": (1090, None, (250, 1023), 60, (60, 140), 72, 661),
    "XL330-M288": (1200, 1750, (445, 2047), 35, (31, 70), 70, 227),
    "XL330-M077": (1190, 1750, (1620, 2047), 35, (31, 70), 70, 227),
    "XC330-M288": (1240, 2352, (350, 2047), 35, (31, 70), 70, 227),
    "XC330-M181": (1230, 2352, (545, 2047), 35, (31, 70), 70, 227),
    "XC330-T288": (1220, 910, (320, 2047), 55, (55, 140), 70, 227),
    "XC330-T181": (1210, 910, (510, 2047), 55, (55, 140), 70, 227),
}
# model: (Velocity I, Velocity P, Position D, Position I, Position P) gains' defaults
GAINS = {
    "XM430-W350": (1920, 100, 0, 0, 800),
    "XH430-W350": (1920, 100, 0, 0, 900),
    "XL430-W250": (1000, 100, 4000, 0, 640),
    "2XL430-W250": (1800, 100, 2000, 0, 640),
    "XL330-M288": (1600, 180, 0, 0, 400),
    "XL330-M077": (400, 40, 0, 400, 400),
    "XC330-M288": (1600, 50, 500, 0, 1100),
    "XC330-M181": (1400, 100, 500, 0, 1200),
    "XC330-T288": (1200, 40, 0, 0, 900),
}
GAIN_NAMES = (
    "velocity_i_gain",
    "velocity_p_gain",
    "position_d_gain",
    "position_i_gain",
    "position_p_gain",
)


def test_every_model_of_the_brief_is_known() -> None:
    assert set(EMANUAL) == set(MODEL_NAMES.values())


@pytest.mark.parametrize("name", sorted(EMANUAL))
def test_a_models_table_holds_its_e_manual_figures(name: str) -> None:
    number, current, (velocity, velocity_top), min_volt, volts, temperature, last = EMANUAL[name]
    spec = MODELS[number]
    assert spec.name == name and spec.page.endswith(f"/dxl/x/{name.lower()}/")
    assert spec.item("model_number").default == number
    if current is None:
        for absent in ("current_limit", "goal_current", "present_current"):
            assert not spec.has(absent)
        assert spec.item_at[38] is None and spec.item_at[102] is None
        assert spec.item("present_load").address == 126
    else:
        assert spec.item("current_limit").default == spec.item("current_limit").high == current
        assert spec.item("goal_current").low == -current
        assert spec.item("present_current").address == 126
    limit = spec.item("velocity_limit")
    assert (limit.address, limit.size, limit.default, limit.high) == (44, 4, velocity, velocity_top)
    assert spec.item("min_voltage_limit").default == min_volt
    for which in ("min_voltage_limit", "max_voltage_limit"):
        assert (spec.item(which).low, spec.item(which).high) == volts
    assert spec.item("temperature_limit").default == temperature
    assert spec.table_end - 1 == last
    assert spec.item(f"indirect_data_{20 if last == 227 else 56}").address == last
    if name in GAINS:
        assert tuple(spec.item(g).default for g in GAIN_NAMES) == GAINS[name]


def test_operating_modes_per_model() -> None:
    assert MODELS[1060].modes == MODELS[1090].modes == {1, 3, 4, 16}
    for number in (1020, 1200, 1220, 1120, 1000):
        assert MODELS[number].modes == {0, 1, 3, 4, 5, 16}


def test_x330_specifics() -> None:
    spec = MODELS[1200]
    assert (spec.item("pwm_slope").address, spec.item("pwm_slope").default) == (62, 140)
    assert MODELS[1220].item("pwm_slope").default == 255
    assert spec.item("baud_rate").high == 6 and MODELS[1020].item("baud_rate").high == 7
    assert spec.item("shutdown").default == 53 and MODELS[1240].item("shutdown").default == 52
    assert spec.item("indirect_address_1").default == 208
    assert spec.item("indirect_address_20").address == 206
    assert spec.item("indirect_address_20").high == 227
    assert not spec.has("indirect_address_21")


def test_x540_external_ports() -> None:
    spec = MODELS[1120]
    assert [spec.item(f"external_port_mode_{n}").address for n in (1, 2, 3)] == [56, 57, 58]
    assert [spec.item(f"external_port_data_{n}").address for n in (1, 2, 3)] == [152, 154, 156]
    assert not MODELS[1020].has("external_port_mode_1")


@pytest.mark.parametrize("number", sorted(MODELS))
def test_items_do_not_overlap_and_eeprom_is_below_64(number: int) -> None:
    taken: set[int] = set()
    for it in MODELS[number].items:
        span = set(range(it.address, it.address + it.size))
        assert not span & taken, it.name
        taken |= span
        assert (it.address < 64) == (it.area is Area.EEPROM), it.name
        assert it.default is None or it.in_range(it.default) or not it.writable, it.name


def test_names_and_numbers() -> None:
    assert model_number("xl430-w250") == 1060 and model_number(1200) == 1200
    with pytest.raises(ValueError, match="unknown motor model 'XM999'"):
        model_number("XM999")
    assert model(4242).name == "model 4242" and model(4242).has("current_limit")
