#!/usr/bin/python3
"""The JSON Schemas of docs/schema/ against the shipped examples and real outputs of `timeopt`.

Every schema is checked against its metaschema (draft 2020-12). Then, in a temporary directory:
- examples/line_problem.json is a problem, examples/planner_config.json a planner configuration
  (also in its written form, every key present);
- the outputs of `timeopt temporal` (optimal, infeasible, a relaxed boundary, every quadrotor limit),
  `timeopt waypoints` (result.json with its flight block, curve.json), `timeopt plan --print-config`,
  `timeopt plan` (the summary on stdout, run from SOURCE_DIR so that it finds maps/) and
  `timeopt simulate` (the flight report; exit 1 expected: the paper's profile exceeds a limit when
  flown) must validate;
- a problem with every key the reader accepts must validate, and be accepted by `timeopt temporal`;
- negative checks, so that the schemas are known to bite: a problem with an unknown key in limits,
  one with max_velocity as a string (both also refused by `timeopt temporal`, exit 2), and a result
  without `status` must fail validation.

Usage: validate_schemas.py TIMEOPT_CLI SOURCE_DIR
Exit codes: 0 every check passed, 1 a check failed (each printed), 2 wrong usage, 77 skipped (no
jsonschema: install Debian's python3-jsonschema). Standard library and jsonschema only.
"""

import copy
import json
import os
import subprocess
import sys
import tempfile
import warnings

try:
    import jsonschema
    from jsonschema import validators
except ImportError as error:  # the test is skipped, saying why
    print(f"SKIP: {error} (install Debian's python3-jsonschema)")
    sys.exit(77)

SCHEMA_FILES = [
    "curve.schema.json",
    "problem.schema.json",
    "result.schema.json",
    "planner_config.schema.json",
    "plan.schema.json",
    "flight_report.schema.json",
    "trajectory.schema.json",
    "polynomial.schema.json",
]
RUN_TIMEOUT_S = 240

failures = []


def report(ok, what, detail=""):
    """One line per check; a failure is remembered and its detail printed under it."""
    print(f"{'ok  ' if ok else 'FAIL'} {what}")
    if not ok:
        failures.append(what)
        for line in detail.rstrip().splitlines():
            print(f"       {line}")
    sys.stdout.flush()
    return ok


def load_json(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)


class Schemas:
    """The schema files, each checked against its metaschema; cross-file $refs ("curve.schema.json",
    "plan.schema.json#/$defs/flight") resolve among them by file name, never over the network."""

    def __init__(self, schema_dir):
        self.store = {}
        for name in SCHEMA_FILES:
            path = os.path.join(schema_dir, name)
            try:
                schema = load_json(path)
                cls = validators.validator_for(schema, default=None)
                if cls is None:
                    raise ValueError(f"unknown or missing $schema: {schema.get('$schema')!r}")
                cls.check_schema(schema)
                missing = [key for key in ("title", "description") if key not in schema]
                if missing:
                    raise ValueError(f"no {', '.join(missing)}")
                if "$id" in schema and "://" in schema["$id"]:
                    raise ValueError(f"$id must be relative, got {schema['$id']!r}")
            except (OSError, ValueError, jsonschema.exceptions.SchemaError) as error:
                report(False, f"schema {name} loads and is a valid schema", str(error)[:2000])
                continue
            self.store[name] = schema
            report(True, f"schema {name}: a valid {cls.__name__} schema")

    def errors(self, instance, name, pointer=""):
        """The validation errors of `instance` against schema file `name` (at JSON pointer `pointer`,
        e.g. "/$defs/written"), as lines; empty when it validates."""
        if name not in self.store:
            return [f"schema {name} did not load"]
        root = self.store[name]
        schema = {"$schema": root["$schema"], "$ref": f"{name}#{pointer}"} if pointer else root
        cls = validators.validator_for(root)
        with warnings.catch_warnings():
            # jsonschema >= 4.18 deprecates RefResolver in favour of `referencing`; Debian 12 has 4.10.
            warnings.simplefilter("ignore", DeprecationWarning)
            # The referrer is stored under base_uri: a wrapper around a sub-schema gets a name of its own.
            base_uri = "wrapper.json" if pointer else name
            resolver = jsonschema.RefResolver(base_uri=base_uri, referrer=schema, store=dict(self.store))
            validator = cls(schema, resolver=resolver)
            try:
                found = sorted(validator.iter_errors(instance), key=lambda e: [str(p) for p in e.absolute_path])
            except jsonschema.exceptions.RefResolutionError as error:
                return [f"unresolvable $ref in {name}: {error}"]
        lines = []
        for error in found[:8]:
            where = "/".join(str(p) for p in error.absolute_path) or "(top level)"
            lines.append(f"{where}: {error.message[:300]}")
            for sub in sorted(error.context or [], key=lambda e: [str(p) for p in e.absolute_path])[:4]:
                sub_where = "/".join(str(p) for p in sub.absolute_path) or "(top level)"
                lines.append(f"    {sub_where}: {sub.message[:200]}")
        if len(found) > 8:
            lines.append(f"... and {len(found) - 8} more")
        return lines

    def expect_valid(self, instance, name, what, pointer=""):
        lines = self.errors(instance, name, pointer)
        return report(not lines, f"{what} validates against {name}{'#' + pointer if pointer else ''}",
                      "\n".join(lines))

    def expect_invalid(self, instance, name, what):
        lines = self.errors(instance, name)
        return report(bool(lines), f"{what} fails {name} (negative check)" +
                      (f": {lines[0]}" if lines else ""),
                      "it validates: the schema does not refuse it")


def run(cli, args, cwd, expected_codes, what):
    """Runs `timeopt ARGS`; reports a failure (with stderr) unless the exit code is expected.
    Returns the completed process, or None when it failed."""
    try:
        proc = subprocess.run([cli] + args, cwd=cwd, capture_output=True, text=True, timeout=RUN_TIMEOUT_S)
    except (OSError, subprocess.TimeoutExpired) as error:
        report(False, f"{what}: timeopt {' '.join(args)}", str(error))
        return None
    if proc.returncode not in expected_codes:
        report(False, f"{what}: timeopt {' '.join(args)} exits {'/'.join(map(str, expected_codes))}",
               f"exit code {proc.returncode}\nstderr: {proc.stderr.strip()[:2000]}")
        return None
    return proc


def validate_file(schemas, path, name, what, pointer=""):
    try:
        instance = load_json(path)
    except (OSError, ValueError) as error:
        report(False, f"{what}: {path} is JSON", str(error))
        return None
    schemas.expect_valid(instance, name, what, pointer)
    return instance


def write_json(path, value):
    with open(path, "w", encoding="utf-8") as f:
        json.dump(value, f, indent=1)
        f.write("\n")
    return path


def main(argv):
    if len(argv) != 3:
        print("usage: validate_schemas.py TIMEOPT_CLI SOURCE_DIR")
        return 2
    cli = os.path.abspath(argv[1])
    source = os.path.abspath(argv[2])
    if not os.access(cli, os.X_OK):
        print(f"FAIL: {cli} is not an executable")
        return 1
    schemas = Schemas(os.path.join(source, "docs", "schema"))
    examples = os.path.join(source, "examples")
    line_problem = os.path.join(examples, "line_problem.json")

    # The shipped examples.
    problem = validate_file(schemas, line_problem, "problem.schema.json", "examples/line_problem.json")
    config_path = os.path.join(examples, "planner_config.json")
    validate_file(schemas, config_path, "planner_config.schema.json", "examples/planner_config.json")
    validate_file(schemas, config_path, "planner_config.schema.json", "examples/planner_config.json",
                  "/$defs/written")

    with tempfile.TemporaryDirectory(prefix="timeopt_schemas_") as tmp:
        def at(name):
            return os.path.join(tmp, name)

        # timeopt temporal: an optimal result.
        result = None
        if run(cli, ["temporal", line_problem, "-o", at("r.json")], tmp, [0], "temporal"):
            result = validate_file(schemas, at("r.json"), "result.schema.json", "temporal result (optimal)")

        # timeopt waypoints: result.json (with its flight block) and curve.json.
        if run(cli, ["waypoints", os.path.join(examples, "waypoints.csv"), "--out-dir", at("wp")], tmp, [0],
               "waypoints"):
            wp_result = validate_file(schemas, at("wp/result.json"), "result.schema.json", "waypoints result.json")
            report(isinstance(wp_result, dict) and "flight" in wp_result,
                   "waypoints result.json has a flight block", "no `flight` key")
            validate_file(schemas, at("wp/curve.json"), "curve.schema.json", "waypoints curve.json")
            # The trajectory file (jerk-limited), its polynomial export, and one without a jerk limit.
            trajectory = validate_file(schemas, at("wp/trajectory.json"), "trajectory.schema.json",
                                       "waypoints trajectory.json")
            if run(cli, ["export", at("wp/trajectory.json"), "--format", "polynomial", "-o", at("poly.json")], tmp,
                   [0], "export --format polynomial"):
                validate_file(schemas, at("poly.json"), "polynomial.schema.json", "export polynomial")
            if isinstance(trajectory, dict):
                both = copy.deepcopy(trajectory)
                both["profile"]["b"] = [[1.0, 1.0]]
                schemas.expect_invalid(both, "trajectory.schema.json", "a trajectory with both b and half_b")
        if run(cli, ["temporal", line_problem, "-o", at("r2.json"), "--trajectory", at("line_t.json")], tmp, [0],
               "temporal --trajectory"):
            validate_file(schemas, at("line_t.json"), "trajectory.schema.json", "temporal --trajectory (linear cells)")

        # timeopt plan --print-config: the complete configuration.
        proc = run(cli, ["plan", "--print-config"], tmp, [0], "plan --print-config")
        if proc:
            try:
                printed = json.loads(proc.stdout)
            except ValueError as error:
                report(False, "plan --print-config prints JSON", str(error))
            else:
                schemas.expect_valid(printed, "planner_config.schema.json", "plan --print-config")
                schemas.expect_valid(printed, "planner_config.schema.json", "plan --print-config",
                                     "/$defs/written")

        # timeopt plan on the default map, from the source tree (it finds maps/ there); the files go
        # to the temporary directory.
        proc = run(cli, ["plan", "-o", at("p.csv"), "--plot", at("p.png")], source, [0], "plan")
        if proc:
            try:
                summary = json.loads(proc.stdout)
            except ValueError as error:
                report(False, "plan prints a JSON summary", str(error))
            else:
                schemas.expect_valid(summary, "plan.schema.json", "plan summary (success)")

        # timeopt simulate: the paper's profile exceeds a limit in flight (exit 1), with a report.
        if run(cli, ["simulate", line_problem, "-o", at("s.json")], tmp, [1], "simulate"):
            validate_file(schemas, at("s.json"), "flight_report.schema.json", "simulate report")

        # An infeasible problem: 10 m line, start at 3 m/s, max_velocity 2 m/s (exit 3, a result).
        infeasible = {
            "curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
            "limits": {"max_velocity": 2.0, "max_acceleration": 1.0},
            "boundary": {"start_velocity": [3, 0, 0]},
        }
        schemas.expect_valid(infeasible, "problem.schema.json", "infeasible problem")
        if run(cli, ["temporal", write_json(at("inf.json"), infeasible), "-o", at("ri.json")], tmp, [3],
               "temporal (infeasible)"):
            ri = validate_file(schemas, at("ri.json"), "result.schema.json", "temporal result (infeasible)")
            report(isinstance(ri, dict) and ri.get("status") == "infeasible" and "infeasibility" in ri,
                   "infeasible result has status infeasible and an infeasibility block",
                   json.dumps(ri)[:500])
        # The same with relax_boundary: optimal, with boundary_relaxation and the infeasibility kept.
        relaxed = dict(infeasible, relax_boundary=True)
        if run(cli, ["temporal", write_json(at("rel.json"), relaxed), "-o", at("rr.json")], tmp, [0],
               "temporal (relaxed boundary)"):
            rr = validate_file(schemas, at("rr.json"), "result.schema.json", "temporal result (relaxed)")
            report(isinstance(rr, dict) and "boundary_relaxation" in rr,
                   "relaxed result has boundary_relaxation", json.dumps(rr)[:500])

        # Every key the reader accepts: null limits, per-axis arrays, an integer-valued 20.0, unknown
        # keys and durations in the curve (ignored / accepted there), every quadrotor limit.
        everything = {
            "curve": {"pieces": [{"x": [0, 10], "y": [0], "z": [0, 2], "comment": "ignored"}],
                      "durations": [2.0], "note": "ignored"},
            "limits": {"max_velocity": None, "max_acceleration": [1, 1, 1], "max_speed": 3, "max_thrust": 12,
                       "min_thrust": 1, "max_tilt": 0.5, "max_acceleration_norm": 2, "gravity": 9.81,
                       "max_acceleration_change": 0.5, "max_jerk": None},
            "boundary": {"start_velocity": [0, 0, 0], "start_acceleration": [0, 0, 0],
                         "end_velocity": [0, 0, 0], "end_acceleration": [0, 0, 0]},
            "discretization": {"K": 20.0},
            "rho": 0.1,
            "constraint_mode": "certified",
            "relax_boundary": False,
        }
        schemas.expect_valid(everything, "problem.schema.json", "problem with every accepted key")
        if run(cli, ["temporal", write_json(at("all.json"), everything), "-o", at("rall.json")], tmp, [0],
               "temporal (every accepted key)"):
            rall = validate_file(schemas, at("rall.json"), "result.schema.json",
                                 "temporal result (quadrotor limits)")
            report(isinstance(rall, dict) and all(k in rall for k in (
                "max_speed_ratio", "max_acceleration_norm_ratio", "max_thrust_ratio", "min_thrust_ratio",
                "max_tilt_ratio")), "quadrotor result has a ratio per quadrotor limit", json.dumps(rall)[:500])

        # Negative checks: the schemas refuse what the reader refuses, and a result without status.
        if isinstance(problem, dict):
            unknown = copy.deepcopy(problem)
            unknown["limits"]["max_velocty"] = 2.0
            schemas.expect_invalid(unknown, "problem.schema.json", "problem with limits.max_velocty (unknown key)")
            run(cli, ["temporal", write_json(at("unknown.json"), unknown)], tmp, [2],
                "reader refuses the unknown key too")
            string = copy.deepcopy(problem)
            string["limits"]["max_velocity"] = "2.0"
            schemas.expect_invalid(string, "problem.schema.json", "problem with max_velocity \"2.0\" (a string)")
            run(cli, ["temporal", write_json(at("string.json"), string)], tmp, [2],
                "reader refuses the string too")
        else:
            report(False, "negative problem checks", "examples/line_problem.json did not load")
        if isinstance(result, dict):
            no_status = {k: v for k, v in result.items() if k != "status"}
            schemas.expect_invalid(no_status, "result.schema.json", "result without status")
        else:
            report(False, "negative result check", "no temporal result to start from")

    if failures:
        print(f"\n{len(failures)} check(s) failed:")
        for what in failures:
            print(f"  {what}")
        return 1
    print("\nall checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
