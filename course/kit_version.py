"""The version of the engine's public grading API, :mod:`ros2course.kit` (a course's ``course.yaml`` names the major version it is written for).

Kept apart from the kit so reading a course manifest does not import the kit (start time of ``list``).
"""

#: bumped in its major part when a kit step changes its arguments or what it records, in its minor
#: part when the kit gains a step (1.1: kit.quotes.id_counts, kit.actions.Goal.cancel_code; 2.0: the
#: kit no longer exports colcon_command, overlay_env and sandbox_run, a grader reaches colcon and the
#: sourced workspace through its session, GradingSession.run_colcon and overlay(); kit.testing.Mutant is
#: DeclaredMutant, apart from dev mutate's generated Mutant)
API_VERSION = "2.10"  # 2.1: kit.scripts.run_script_first (discovery steps, issue 37); 2.2: kit.rate(median=...);
# 2.3: GradingSession.random (a grader's probes drawn per submission content); 2.4 (issue 38): kit.Session (the
# Protocol graders are typed with), kit.services and kit.learner_files (steps two lessons used, from graders/),
# kit.checks.spins + kit.params.record_spins, kit.sigint_exit(again=...) (a second run after rclpy's race)
# 2.5: kit.actions.offer_once_it_waits, kit.quotes.counts_from_zero(sequence=) with
# TopicProbe.sequence_numbers (verdicts no discovery race decides), kit.launch NodeAction.refused
# 2.6 (issue 38): TopicProbe.matched_since; kit steps typed with kit.Session (the session is composed of a
# verdict book, grade.verdicts, an observer, grade.observer, and a machine view, grade.machine; nothing a grader
# uses changed); kit.component_type (one refusal for an optional component's interface type: nav2, Gazebo)
# 2.7: Session.wanted (a check whose verdict cannot matter under dev validate --until-settled)
# 2.8: kit.sigint_exit fails rclpy's race error seen in RACE_RUNS runs in a row (the program's: main() called
# twice), kit.programs.judge_interrupted_run allows a script's node's race (launch-and-run decided it by itself)
# 2.9: kit.ctrl_c_once_it_logs (a waiting program's Ctrl+C: the actions client's, Gazebo's and Nav2's own copies);
# sigint_exit judges a fresh run that exited before it was ready (it was skipped, and the race counted as clean);
# run.process.rclpy_shutdown_race knows rclpy's global-executor race; kit.topics_services.fields judges the order
# 2.10: kit.sigint_exit presses Ctrl+C while the node's main thread waits (run.process.LearnerProcess.wait_idle:
# a press during a callback ends rclpy.spin() with no ExternalShutdownException, and the Humble habit passed)
