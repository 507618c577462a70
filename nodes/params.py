"""Declaring a node's parameters with descriptors: a description, read-only, a range and
what values are allowed, checked at start with one error naming the parameter.

A node declares its parameters from a table (:func:`declare_table`), so that its constructor
says what it builds rather than how each parameter is declared.
"""
import math

from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                              ParameterUninitializedException)
from rclpy.parameter import Parameter

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

#: Array defaults in a parameter table (:func:`declare_table`): an array parameter is declared
#: by its type, without default (rclpy cannot infer the type of ``[]``); unset means ``[]``.
DOUBLES, INTEGERS, STRINGS = (Parameter.Type.DOUBLE_ARRAY, Parameter.Type.INTEGER_ARRAY,
                              Parameter.Type.STRING_ARRAY)
#: The ends of an integer range open on that side (rcl_interfaces' IntegerRange is int64).
INT64_MIN, INT64_MAX = -2 ** 63, 2 ** 63 - 1

_TYPE_TEXT = {Parameter.Type.BOOL: "a bool", Parameter.Type.INTEGER: "an integer",
              Parameter.Type.DOUBLE: "a number", Parameter.Type.STRING: "a string",
              Parameter.Type.BOOL_ARRAY: "a list of bools",
              Parameter.Type.INTEGER_ARRAY: "a list of integers",
              Parameter.Type.DOUBLE_ARRAY: "a list of numbers",
              Parameter.Type.STRING_ARRAY: "a list of strings"}


def _number(value):
    return f"{value:g}" if isinstance(value, float) else str(value)


def allowed_text(parameter_type, range=None, positive=False, finite=False, choices=None):
    """What a parameter accepts, as the descriptor's constraints and the errors say it:
    "an integer >= 1", "a finite number > 0", "a number in [0, 1]", "one of 'a', 'b'"."""
    if choices:
        return "one of " + ", ".join(repr(choice) for choice in choices)
    text = _TYPE_TEXT[parameter_type]
    if parameter_type == Parameter.Type.DOUBLE and finite:
        text = "a finite number"
    low, high = range if range is not None else (None, None)
    if positive:
        low = None if low is not None and low <= 0 else low
        return f"{text} > 0" + (f" and <= {_number(high)}" if high is not None else "")
    if low is not None and high is not None:
        return f"{text} in [{_number(low)}, {_number(high)}]"
    if low is not None:
        return f"{text} >= {_number(low)}"
    if high is not None:
        return f"{text} <= {_number(high)}"
    return text


def parameter_descriptor(parameter_type, description, *, read_only=True, range=None,
                         positive=False, finite=False, choices=None, additional_constraints=""):
    """An rcl_interfaces ParameterDescriptor: ``description`` (what it is, its unit),
    ``read_only`` (a change at run time would not take effect), ``range`` = (low, high), both
    inclusive, None for an open side, as an IntegerRange or FloatingPointRange (rclpy then
    refuses values outside it), and in ``additional_constraints`` what values are allowed
    (:func:`allowed_text`) followed by ``additional_constraints``."""
    descriptor = ParameterDescriptor(description=description, type=parameter_type.value,
                                     read_only=read_only)
    if positive:
        range = (0, None if range is None else range[1])
    if range is not None:
        low, high = range
        if parameter_type == Parameter.Type.INTEGER:
            descriptor.integer_range = [IntegerRange(
                from_value=INT64_MIN if low is None else int(low),
                to_value=INT64_MAX if high is None else int(high), step=0)]
        elif parameter_type == Parameter.Type.DOUBLE:
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=-math.inf if low is None else float(low),
                to_value=math.inf if high is None else float(high), step=0.0)]
        else:
            raise ValueError(f"a range needs an integer or double parameter, not "
                             f"{parameter_type.name}")
    constraints = []
    if range is not None or positive or finite or choices:
        constraints.append(allowed_text(parameter_type, range, positive, finite, choices))
    if additional_constraints:
        constraints.append(additional_constraints)
    descriptor.additional_constraints = "; ".join(constraints)
    return descriptor


def declare(node, name, default, description, *, read_only=True, range=None, positive=False,
            finite=False, choices=None, additional_constraints=""):
    """Declare the parameter ``name`` with its default and a descriptor
    (:func:`parameter_descriptor`; the type is the default's) and return its value.

    ``range`` = (low, high), inclusive, None for an open side: rclpy refuses values outside
    it, at start and at run time. ``positive`` (> 0), ``finite`` (no inf/NaN) and ``choices``
    (the allowed values) are checked here, at start. Read-only parameters (the default: the
    nodes read their parameters once, at start) are refused at run time by rclpy. A value
    that breaks any of this raises ValueError "the parameter NAME must be ALLOWED, got VALUE"
    (one FATAL line with :func:`serve` and :func:`run_job`), also for a value of the wrong
    type.
    """
    parameter_type = Parameter.Type.from_parameter_value(default)
    descriptor = parameter_descriptor(
        parameter_type, description, read_only=read_only, range=range, positive=positive,
        finite=finite, choices=choices, additional_constraints=additional_constraints)
    allowed = allowed_text(parameter_type, range, positive, finite, choices)
    value = _declared(node, name, default, descriptor, allowed)
    bad = ((choices and value not in choices)
           or (positive and not value > 0)
           or (finite and not math.isfinite(value)))
    if bad:
        raise ValueError(f"the parameter {name} must be {allowed}, got {value!r}")
    return value


def declare_array(node, name, parameter_type, description, *, read_only=True,
                  additional_constraints=""):
    """Declare an array parameter without default (rclpy cannot infer the type of ``[]``),
    with a descriptor as :func:`declare`; unset means ``[]``. Returns a list."""
    descriptor = parameter_descriptor(parameter_type, description, read_only=read_only,
                                      additional_constraints=additional_constraints)
    value = _declared(node, name, parameter_type, descriptor, _TYPE_TEXT[parameter_type])
    return list(value or [])


def _declared(node, name, default, descriptor, allowed):
    """``node.declare_parameter`` whose refusal of the given value (out of range, wrong type)
    is a ValueError naming the parameter and what it accepts."""
    try:
        parameter = node.declare_parameter(name, default, descriptor)
    except (InvalidParameterValueException, InvalidParameterTypeException):
        given = getattr(node, "_parameter_overrides", {}).get(name)
        raise ValueError(f"the parameter {name} must be {allowed}, got "
                         f"{given.value if given is not None else '?'!r}") from None
    try:
        return parameter.value
    except ParameterUninitializedException:
        return None


def describe_use_sim_time(node):
    """Give rclpy's own ``use_sim_time`` parameter a description (it has none); it stays
    writable: rclpy's time source follows it at run time."""
    if node.has_parameter("use_sim_time"):
        descriptor = node.describe_parameter("use_sim_time")
        if not descriptor.description:
            descriptor.description = ("take this node's ROS clock from the /clock topic "
                                      "(standard ROS parameter, handled by rclpy)")
            node.set_descriptor("use_sim_time", descriptor)


def declare_table(node, table):
    """Declare the parameters of ``table`` in its order; their values by name.

    A row is ``(name, default, description)`` or ``(name, default, description,
    constraints)``, constraints being :func:`declare`'s keywords; a default of
    :data:`DOUBLES`, :data:`INTEGERS` or :data:`STRINGS` declares an array parameter without
    default (:func:`declare_array`), whose unset value is ``[]``.
    """
    values = {}
    for name, default, description, *constraints in table:
        options = constraints[0] if constraints else {}
        if isinstance(default, Parameter.Type):
            values[name] = declare_array(node, name, default, description, **options)
        else:
            values[name] = declare(node, name, default, description, **options)
    return values
