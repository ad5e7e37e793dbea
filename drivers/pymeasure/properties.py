"""The public properties each preset instrument class declares (PyMeasure's
``Instrument.control``, ``measurement`` and ``setting``, and plain properties), read from
the classes by tools/pymeasure_properties.py (generated: do not edit): the rig file's
property names are checked against them at load without importing PyMeasure."""

from collections.abc import Mapping


def _names(text: str) -> frozenset[str]:
    return frozenset(text.split())


PROPERTIES: Mapping[str, frozenset[str]] = {
    "pymeasure.instruments.keithley.Keithley2000": _names(
        """
        beep_state buffer_data buffer_points complete current current_ac_bandwidth
        current_ac_digits current_ac_nplc current_ac_range current_ac_reference
        current_digits current_nplc current_range current_reference frequency
        frequency_aperature frequency_digits frequency_reference frequency_threshold id
        mode next_error options period period_aperature period_digits period_reference
        period_threshold resistance resistance_4W_digits resistance_4W_nplc
        resistance_4W_range resistance_4W_reference resistance_digits resistance_nplc
        resistance_range resistance_reference status temperature temperature_digits
        temperature_nplc temperature_reference trigger_count trigger_delay voltage
        voltage_ac_bandwidth voltage_ac_digits voltage_ac_nplc voltage_ac_range
        voltage_ac_reference voltage_digits voltage_nplc voltage_range voltage_reference
        """
    ),
    "pymeasure.instruments.keithley.Keithley6517B": _names(
        """
        buffer_data buffer_points complete current current_nplc current_range error id
        next_error options resistance resistance_nplc resistance_range
        source_current_resistance_limit source_enabled source_voltage
        source_voltage_range status voltage voltage_nplc voltage_range
        """
    ),
    "pymeasure.instruments.srs.SR830": _names(
        """
        adc1 adc2 adc3 adc4 aux_in_1 aux_in_2 aux_in_3 aux_in_4 aux_out_1 aux_out_2
        aux_out_3 aux_out_4 buffer_count channel1 channel2 complete dac1 dac2 dac3 dac4
        err_status filter_slope filter_synchronous frequency harmonic id input_config
        input_coupling input_grounding input_notch_config lia_status magnitude
        next_error options phase reference_source reference_source_trigger reserve
        sample_frequency sensitivity sine_voltage status theta time_constant x xy y
        """
    ),
    "pymeasure.instruments.srs.SR860": _names(
        """
        adc1 adc2 adc3 adc4 aux_in_1 aux_in_2 aux_in_3 aux_in_4 aux_out_1 aux_out_2
        aux_out_3 aux_out_4 complete dac1 dac2 dac3 dac4 dcmode detectedfrequency
        extfreqency filer_synchronous filter_advanced filter_slope filter_synchronous
        frequency frequencypreset1 frequencypreset2 frequencypreset3 frequencypreset4
        front_panel get_noise_bandwidth get_signal_strength_indicator gettimebase
        harmonic harmonicdual horizontal_time_div id input_config input_coupling
        input_current_gain input_grounding input_range input_shields input_signal
        input_voltage_mode internalfrequency magnitude next_error options parameter_DAT1
        parameter_DAT2 parameter_DAT3 parameter_DAT4 phase reference_externalinput
        reference_source reference_source_trigger reference_triggermode screen_layout
        sensitivity sensitvity sine_amplitudepreset1 sine_amplitudepreset2
        sine_amplitudepreset3 sine_amplitudepreset4 sine_dclevelpreset1
        sine_dclevelpreset2 sine_dclevelpreset3 sine_dclevelpreset4 sine_voltage status
        strip_chart_dat1 strip_chart_dat2 strip_chart_dat3 strip_chart_dat4 theta
        time_constant timebase x y
        """
    ),
    "pymeasure.instruments.thorlabs.ThorlabsPM100USB": _names(
        """
        complete energy id next_error options power status wavelength wavelength_max
        wavelength_min
        """
    ),
}
