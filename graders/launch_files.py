"""Grader for ``launch-files`` (seed ch. 22.7-22.11 and 23; contract in shared/LESSONS.md).

The launch file is taken from where ``ros2 launch`` takes it: the installed
``share/<pkg>/launch/`` folder, and run with the real launch_ros as ``ros2
launch`` runs it (see :mod:`ros2course.kit.launch`; on the PyPI install launch_ros
comes from the source-built underlay). Then the graph is watched, black-box:
node name, topic, rate and message contents. The file is also read statically,
only to say which ``Node(...)`` actions it holds when launch started too little.

The values must come from the launch file, not from the node's code: the executable is then started
alone (``ros2 run``, no launch file, a graph of its own), and its parameters must still hold the
parameters lesson's defaults (``defaults_kept``; a node whose defaults were edited to the launch file's
values publishes the same messages when launched).
"""

from __future__ import annotations

from ros2course.kit import LATE_DELIVERY
from ros2course import kit
from ros2course.kit import Check, Session, Unmet, params, quotes
from ros2course.kit.launch import installed_launch_file, launched_node, start_launch_file
from ros2course.kit.quotes import LAUNCH_FILE, LAUNCH_NODE, LAUNCH_PERIOD, LAUNCH_TOPIC

SAMPLES = 6  # messages -> 5 intervals at 4 Hz (the minimum shared/LESSONS.md asks for)
NODE_TIMEOUT = 10.0  # seconds for the node to appear (launch_ros start-up included)

#: Seconds of observation the contract needs: first message after one period, then 5 intervals.
WINDOW = SAMPLES * LAUNCH_PERIOD

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("launch_installed", f"launch/{LAUNCH_FILE} is installed in share/{quotes.PACKAGE}/launch", 2,
          "add (os.path.join('share', package_name, 'launch'), glob(os.path.join('launch', '*launch.[pxy][yma]*'))) "
          "to data_files in setup.py, then colcon build"),
    Check("launch_starts", "The launch file starts amazing_quote_configurable_publisher_node", 2,
          "a Node(package='python_package_that_uses_parameters_and_launch_files', "
          "executable='amazing_quote_configurable_publisher_node', ...) in the LaunchDescription returned by "
          "generate_launch_description()"),
    Check("node_name", f"The node is named {LAUNCH_NODE}", 2, f"give Node(...) name='{LAUNCH_NODE}'"),
    Check("topic", f"It publishes AmazingQuote on /{LAUNCH_TOPIC}", 2,
          f"parameters=[{{'topic_name': '{LAUNCH_TOPIC}', ...}}] in Node(...)"),
    Check("rate", "It publishes at 4 Hz (period 0.25 s)", 2, "'period': 0.25 in the parameters dict (a float)",
          needs=("topic",)),
    Check("contents", "The messages carry the ch. 22.9 quote and philosopher Tyler", 2,
          "'quote' and 'philosopher_name': 'Tyler' in the parameters dict; adjacent string literals are glued "
          "without a space, so mind the spaces at the ends of the pieces", needs=("topic",)),
    Check("launched_parameters", "The launched node's parameters are the launch file's values", 1,
          "pass all four in Node(..., parameters=[{'topic_name': ..., 'period': 0.25, 'quote': ..., "
          "'philosopher_name': 'Tyler'}]): not a remapping for the topic, nor a value written in the node's code",
          needs=("node_name",)),
    Check("defaults_kept", "The values come from the launch file: the node's own defaults are unchanged", 2,
          "leave amazing_quote_configurable_publisher_node.py as the parameters lesson made it (defaults quote "
          "'Use the force, Pikachu!', philosopher_name 'Uncle Ben', topic_name 'amazing_quote', period 0.5) and "
          "pass the new values as parameters=[{...}] of Node(...) in the launch file", part="defaults"),
]


def grade(s: Session) -> None:
    """Start the launch file, then watch the node, its topic, rate and messages."""
    with s.part("defaults", own_graph=True):  # first: a launch file that is missing ends the grading's main part
        _defaults_kept(s)
    launch_file = installed_launch_file(s, "launch_installed", quotes.PACKAGE, LAUNCH_FILE, quotes.package_source(s))
    probe = s.ros.topic(f"/{LAUNCH_TOPIC}", quotes.amazing_quote(s))
    with s.phase("start"):
        run = start_launch_file(s, launch_file)
    mode = run.mode
    launched_node(s, "launch_starts", "node_name", run, quotes.PACKAGE, quotes.EXECUTABLE, LAUNCH_NODE, NODE_TIMEOUT)
    with s.phase("observe"):
        timeout = probe.observe(SAMPLES, LAUNCH_PERIOD, 4.0 + LATE_DELIVERY, abort=lambda: not run.any_running())
    samples = probe.samples()
    s.record("topic", bool(samples), f"{len(samples)} AmazingQuote message(s) on /{LAUNCH_TOPIC} ({mode})"
             if samples else f"no message on /{LAUNCH_TOPIC} within {timeout:.1f} s ({mode}); "
             f"topics seen: {kit.topics_seen(s.ros)}", f"AmazingQuote messages on /{LAUNCH_TOPIC}")
    kit.rate(s, "rate", probe.send_stamps(), period=LAUNCH_PERIOD, needed=SAMPLES, waited=timeout,
             noun="message", source="the messages' send stamps")
    quotes.texts(s, "contents", [m for _, m in samples], quotes.LAUNCH_QUOTE, quotes.LAUNCH_PHILOSOPHER, "ch. 22.9")
    _launched_parameters(s, run)
    with s.phase("stop"):
        for proc in run.processes:
            proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)


def _defaults_kept(s: Session) -> None:
    """Record ``defaults_kept``: the executable started alone (no launch file, no ``-p``) declares the
    parameters lesson's defaults (:data:`ros2course.kit.quotes.DEFAULTS`), read through its parameter
    services (``ros2 param get``).

    Raises:
        Unmet: no executable, or its parameter services never answered.
    """
    path, why = s.find_executable(quotes.PACKAGE, quotes.EXECUTABLE)
    if path is None:
        raise Unmet(why)
    proc = s.launch(path, f"{quotes.EXECUTABLE}.alone")
    services = params.connect(s, quotes.NODE, proc=proc, timeout=NODE_TIMEOUT)
    values = services.get(list(quotes.DEFAULTS))
    changed = {name: value for name, (_, value) in values.items() if value != quotes.DEFAULTS[name]}
    launch_values = {"topic_name": LAUNCH_TOPIC, "period": LAUNCH_PERIOD, "quote": quotes.LAUNCH_QUOTE,
                     "philosopher_name": quotes.LAUNCH_PHILOSOPHER}
    observed = ("started alone, it declares the parameters lesson's defaults" if not changed else
                "started alone, its defaults are " + "; ".join(
                    f"{name} {_show(value)}" + (" (the launch file's value)"
                                                              if value == launch_values[name] else "")
                    for name, value in changed.items()) + ": the node's code was changed")
    s.record("defaults_kept", not changed, observed, "started alone (no launch file): " + ", ".join(
        f"{name} {_show(value)}" for name, value in quotes.DEFAULTS.items()))
    proc.stop(sigint_timeout=2.0, sigterm_timeout=2.0)


def _launched_parameters(s: Session, run) -> None:
    """Record ``launched_parameters``: the node the launch file started declares its four values
    (:data:`ros2course.kit.quotes.LAUNCH_PARAMETERS`, read through its parameter services as ``ros2 param get``
    does). What the topic shows alone can come from elsewhere: a ``remappings=`` for the topic, a period written
    in the node's code with the launch file's 'period' left out (helper audit of issue 37); the lesson asks for
    the values in the launch file, "with no change to the node's code"."""
    expected = "ros2 param get on the launched node: " + ", ".join(
        f"{name} {_show(value)}" for name, value in quotes.LAUNCH_PARAMETERS.items())
    try:
        services = params.connect(s, LAUNCH_NODE, proc=run.processes[0] if run.processes else None,
                                  timeout=NODE_TIMEOUT)
        values = services.get(list(quotes.LAUNCH_PARAMETERS))
    except Unmet as exc:
        s.record("launched_parameters", False, str(exc), expected)
        return
    wrong = {name: value for name, (_, value) in values.items() if value != quotes.LAUNCH_PARAMETERS[name]}
    s.record("launched_parameters", not wrong, "the launched node declares the launch file's values" if not wrong
             else "the launched node has " + "; ".join(f"{name} {_show(value)}" for name, value in wrong.items())
             + ": pass every value as a parameter in the launch file", expected)


def _show(value) -> str:
    """A parameter value as ros2 param get shows it: text quoted and shortened, numbers as they are."""
    return quotes.short(value) if isinstance(value, str) else repr(value)

