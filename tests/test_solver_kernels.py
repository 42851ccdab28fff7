"""The compiled solver kernels (issue #9): the same numbers as CasADi's own evaluation and AD, a
disk cache that is safe to share between processes, and a walk that runs without a compiler."""
import hashlib
import json
import os
import shutil
import subprocess
import sys
import textwrap
import threading
import warnings
from collections import Counter
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from klaw_ocp.config import load_config
from klaw_ocp import kernel_calls, kernels
from klaw_ocp.solvers import MultipleShootingSolver, integrator, ipopt_nlp
from klaw_ocp.solvers.integrator import SubphaseKernels, rk4_interval, subphase_kernels
from klaw_ocp.walk import simulate_walk, walk_spec

ROOT = Path(__file__).resolve().parents[1]


def _machine_has_a_compiler() -> bool:
    """Whether compiled kernels are expected here: KLAW_OCP_JIT not off and a C compiler on PATH.
    Looked up independently of :func:`kernels.compiler`, so that a bug making klaw_ocp miss a
    compiler that is there fails the tests below instead of skipping them."""
    if os.environ.get("KLAW_OCP_JIT", "1").strip().lower() in ("0", "off", "false", "no"):
        return False
    names = [os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"]
    return any(shutil.which(name) for name in names)


#: the compile path needs a C compiler; without one, the CasADi fallback is what runs (tested below)
requires_compiler = pytest.mark.skipif(not _machine_has_a_compiler(), reason="no C compiler on this machine")


@pytest.fixture(scope="module")
def problems():
    """One real problem of each subphase: the first two steps of the natural walk."""
    captured = {}
    original = MultipleShootingSolver.solve

    def spy(self, pb):
        captured.setdefault(pb.spec.name, pb)
        return original(self, pb)
    MultipleShootingSolver.solve = spy
    try:
        spec = walk_spec(load_config(ROOT / "configs" / "natural_walk.yaml"))
        simulate_walk(replace(spec, plans=spec.plans[:2]))
    finally:
        MultipleShootingSolver.solve = original
    return captured


def _points(pb, k):
    """The problem's guess simulated: realistic interval start states."""
    n = pb.grid.size - 1
    xs = k.sim(pb.x0, pb.grid[:-1], np.diff(pb.grid), pb.guess, pb.context)[0].reshape(n, -1)
    return np.vstack([pb.x0, xs[:-1]])


@pytest.mark.parametrize("name", ["stance", "swing1", "swing2", "swing3"])
def test_interval_sensitivities_are_the_derivative_of_the_interval(problems, name):
    """The sens kernel propagates the variational equations through the RK4 stages: it must equal
    CasADi's AD of the whole RK4 interval, block for block."""
    pb = problems[name]
    spec, k = pb.spec, subphase_kernels(pb.spec, 4, pb.grid.size - 1)
    starts, t, h = _points(pb, k), pb.grid[:-1], np.diff(pb.grid)
    xf, jac = k.sens(starts, t, h, pb.guess, pb.context)
    n, nx, nu = len(t), spec.nx, spec.nu
    jac = jac.reshape(n, nx + nu, nx).transpose(0, 2, 1)
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    ts, hs, cs = ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("c", spec.nc)
    out = rk4_interval(spec, 4, False).expand()(x, ts, hs, u, cs)   # the interval itself, one SX graph
    reference = ca.Function("ref", [x, ts, hs, u, cs], [out, ca.jacobian(out, ca.vertcat(x, u))])
    for i in (0, n // 2, n - 1):
        ref_x, ref_j = (np.asarray(v) for v in reference(starts[i], t[i], h[i], pb.guess, pb.context))
        np.testing.assert_allclose(xf.reshape(n, nx)[i], ref_x.ravel(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(jac[i], ref_j, rtol=1e-9, atol=1e-9 * np.abs(ref_j).max())


@requires_compiler
def test_compiled_and_casadi_evaluation_agree(problems, monkeypatch):
    """Without a compiler the same kernels are evaluated by CasADi: same numbers to round-off."""
    pb = problems["swing2"]
    compiled = subphase_kernels(pb.spec, 4, pb.grid.size - 1)
    assert compiled.library.compiled
    monkeypatch.setenv("KLAW_OCP_JIT", "0")
    plain = SubphaseKernels(pb.spec, 4, pb.grid.size - 1)
    starts, t, h = _points(pb, compiled), pb.grid[:-1], np.diff(pb.grid)
    args = {"sim": (pb.x0, t, h, pb.guess, pb.context), "prop": (starts, t, h, pb.guess, pb.context),
            "sens": (starts, t, h, pb.guess, pb.context), "final": (starts[-1], pb.context),
            "nodes": (np.vstack([starts, starts[-1]]), pb.grid, pb.guess, pb.context)}
    for name, a in args.items():
        for c_out, p_out in zip(getattr(compiled, name)(*a), getattr(plain, name)(*a)):
            np.testing.assert_allclose(c_out, p_out, rtol=1e-11, atol=1e-11, err_msg=name)
    assert not plain.library.compiled


def test_ipopt_constraint_jacobian_equals_ad(problems):
    """IPOPT's Jacobian, assembled from the per-interval blocks, is CasADi's AD of the constraints."""
    pb = problems["swing2"]
    spec, n = pb.spec, pb.grid.size - 1
    nlp, _, jac_g, _ = ipopt_nlp._build(spec, n, 4, compiling=False)
    z, p = ca.MX.sym("z", nlp.size1_in(0)), ca.MX.sym("p", nlp.size1_in(1))
    ad = ca.Function("ad", [z, p], [ca.jacobian(nlp(z, p)[1], z)])
    k = subphase_kernels(spec, 4, n)
    xs = k.sim(pb.x0, pb.grid[:-1], np.diff(pb.grid), pb.guess, pb.context)[0]
    z0 = np.concatenate([xs, pb.guess])
    p0 = np.concatenate([pb.x0, pb.grid, pb.context, pb.guess, pb.scale, np.ones(spec.nu)])
    expected, got = np.asarray(ca.densify(ad(z0, p0))), np.asarray(ca.densify(jac_g(z0, p0)[1]))
    np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)


def _tiny_library(tmp_cache, counter, tag="a", power=2):
    def build(compiling):
        counter.append(compiling)
        x = ca.SX.sym("x", 3)
        return [ca.Function("tiny_square", [x], [x ** power]), ca.Function("tiny_sum", [x], [ca.sum1(x)])]
    return kernels.KernelLibrary(["tiny", tag], ["tiny_square", "tiny_sum"], build)


@requires_compiler
def test_cache_hit_builds_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    calls = []
    first = _tiny_library(tmp_path, calls).functions()
    assert calls == [True]
    np.testing.assert_array_equal(first["tiny_square"]([1.0, 2.0, 3.0])[0], [1.0, 4.0, 9.0])
    library = _tiny_library(tmp_path, calls)
    assert library.functions()["tiny_sum"]([1.0, 2.0, 3.0])[0][0] == 6.0
    assert calls == [True], "a cache hit must not build the CasADi functions again"
    assert (library.path.stat().st_mode & 0o777) == 0o755
    other = _tiny_library(tmp_path, calls, tag="b")
    other.load()
    assert other.path != library.path, "other key parts, another library"
    assert not list(tmp_path.rglob(".build-*")), "no temporary build folder left behind"


@requires_compiler
def test_a_damaged_library_is_rebuilt(tmp_path, monkeypatch):
    """A cached file that is not the library its stamp names is compiled again, with a one-line
    note, before it is ever loaded: never written in place here (a library in use is not
    touched), it is damaged before this process loads it."""
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    calls = []
    library = _tiny_library(tmp_path, calls, tag="damaged")
    path = library.library_path()
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a shared library")
    with pytest.warns(kernels.KernelCacheNote, match="has no readable checksum"):
        assert library.functions()["tiny_sum"]([1.0, 1.0, 1.0])[0][0] == 3.0
    assert library.compiled and library.path == path and calls == [True]


def _cached_pair(tmp_path, tag, power=2):
    """A library compiled into the cache and its checksum stamp (paths), not loaded: a library
    this process has mapped must not be written in place (that is a crash, not a test)."""
    library = _tiny_library(tmp_path, [], tag=tag, power=power)
    path = library.library_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    library._compile(kernels.compiler(), path.parent, path)
    return path, path.with_suffix(".sha256")


@requires_compiler
@pytest.mark.parametrize("damage", ["truncated", "another kernel's library", "another kernel's pair",
                                    "stamp missing", "stamp garbled"])
def test_a_cached_library_is_verified_before_it_is_loaded(tmp_path, monkeypatch, damage):
    """Loading a truncated library can kill the process (SIGBUS) and another kernel's loads other
    symbols: each is found by its stamp (key and SHA-256, written with it) and rebuilt once, with
    one note; the rebuilt library computes, and its stamp matches it again."""
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    path, stamp = _cached_pair(tmp_path, "victim")
    # another kernel with the same symbols: loaded, it would compute x^3 without a word
    other, other_stamp = _cached_pair(tmp_path, "other", power=3)
    if damage == "truncated":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif damage == "another kernel's library":
        path.write_bytes(other.read_bytes())
    elif damage == "another kernel's pair":
        path.write_bytes(other.read_bytes())
        stamp.write_bytes(other_stamp.read_bytes())
    elif damage == "stamp missing":
        stamp.unlink()
    else:
        stamp.write_bytes(b"\xff\xfe garbage")
    calls = []
    library = _tiny_library(tmp_path, calls, tag="victim")
    with pytest.warns(kernels.KernelCacheNote) as notes:
        assert library.functions()["tiny_square"]([1.0, 2.0, 3.0])[0].tolist() == [1.0, 4.0, 9.0]
    assert len(notes) == 1 and "\n" not in str(notes[0].message) and str(path) in str(notes[0].message)
    assert calls == [True] and library.compiled
    assert library._damage(path) is None, "the rebuilt library matches its stamp"


@requires_compiler
def test_a_library_that_verifies_loads_without_a_note(tmp_path, monkeypatch):
    import warnings
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    _cached_pair(tmp_path, "fine")
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _tiny_library(tmp_path, calls, tag="fine").functions()["tiny_sum"]([1.0, 2.0, 3.0])[0][0] == 6.0
    assert calls == []


def test_the_command_line_shows_the_packages_notes_in_one_line(capsys):
    from klaw_ocp import cli
    cli._one_line_warning(kernels.KernelCacheNote("klaw_ocp: the cached solver kernel /c/k.so does not match "
                                                  "its checksum (damaged or replaced); rebuilding it"),
                          kernels.KernelCacheNote, "kernels.py", 1)
    err = capsys.readouterr().err
    assert err == ("klaw-ocp: the cached solver kernel /c/k.so does not match its checksum (damaged or "
                   "replaced); rebuilding it\n")


#: a child process that builds (or finds) the "race" library and reports what it did as JSON
_RACE_SCRIPT = textwrap.dedent("""
    import hashlib, json, os, subprocess, sys, time
    from pathlib import Path
    import casadi as ca
    from klaw_ocp.kernels import KernelLibrary
    sync, racers = Path(sys.argv[1]), int(sys.argv[2])
    report = {"built": False}
    run = subprocess.run

    def compiler_run(cmd, *args, **kwargs):
        if "-o" not in cmd:                 # the compiler's --version, not a build
            return run(cmd, *args, **kwargs)
        # a barrier across the processes: no build finishes (so none can be found in the cache)
        # before every racer has started its own; the builds overlap
        (sync / f"compiling-{os.getpid()}").touch()
        deadline = time.monotonic() + 60
        while len(list(sync.glob("compiling-*"))) < racers and time.monotonic() < deadline:
            time.sleep(0.005)
        report["together"] = len(list(sync.glob("compiling-*"))) >= racers
        result = run(cmd, *args, **kwargs)
        out = Path(cmd[cmd.index("-o") + 1])
        stat = out.stat()
        report.update(built=True, output=str(out.resolve()), inode=[stat.st_dev, stat.st_ino],
                      size=stat.st_size, sha=hashlib.sha256(out.read_bytes()).hexdigest())
        return result

    subprocess.run = compiler_run

    def build(compiling):
        x = ca.SX.sym("x", 4)
        return [ca.Function("race", [x], [ca.sin(x) * ca.cos(x) + x ** 3])]

    lib = KernelLibrary(["race"], ["race"], build)
    values = lib.functions()["race"]([0.1, 0.2, 0.3, 0.4])[0]
    report.update(compiled=lib.compiled, path=str(lib.path.resolve()) if lib.path else None,
                  values=values.tolist())
    print(json.dumps(report))
""")


@requires_compiler
def test_processes_may_build_the_same_library_at_once(tmp_path, monkeypatch):
    """Sweep workers may build the same library at once: here four processes all build it, at the
    same time (a barrier in front of their compilers), each into a file of its own; the cache
    then holds one of those files, whole, renamed into place (never written to in place, never
    a mix of two builds), which every racer loaded and a fresh loader finds without building."""
    racers, cache, sync = 4, tmp_path / "cache", tmp_path / "sync"
    sync.mkdir()
    env = dict(os.environ, KLAW_OCP_CACHE_DIR=str(cache))
    procs = [subprocess.Popen([sys.executable, "-c", _RACE_SCRIPT, str(sync), str(racers)], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(racers)]
    outputs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), [err for _, err in outputs]
    reports = [json.loads(out.strip().splitlines()[-1]) for out, _ in outputs]
    assert all(r["built"] for r in reports), "every racer built the library (none found it in the cache)"
    assert all(r["together"] for r in reports), "the four builds ran at the same time"
    x = np.array([0.1, 0.2, 0.3, 0.4])
    expected = np.sin(x) * np.cos(x) + x ** 3
    libraries = list(cache.rglob("*.so"))
    assert len(libraries) == 1 and not list(cache.rglob(".build-*"))
    final = libraries[0].resolve()
    for r in reports:
        assert r["compiled"] and r["path"] == str(final), r
        # libm's and numpy's sin/cos may differ by an ulp or two: 1e-13 is round-off, not a defect
        np.testing.assert_allclose(r["values"], expected, rtol=1e-13, atol=0)
    outputs = {r["output"] for r in reports}
    assert len(outputs) == racers and str(final) not in outputs, "each build writes a file of its own"
    stat = final.stat()
    winners = [r for r in reports if r["inode"] == [stat.st_dev, stat.st_ino]]
    assert len(winners) == 1, "the cached library is one build's file moved into place, not a copy"
    assert (winners[0]["size"], winners[0]["sha"]) == (stat.st_size, hashlib.sha256(final.read_bytes()).hexdigest())
    assert (stat.st_mode & 0o777) == 0o755
    # a fresh loader (this process) finds the library, builds nothing, gets the same numbers
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(cache))
    calls = []

    def build(compiling):
        calls.append(compiling)
        y = ca.SX.sym("x", 4)
        return [ca.Function("race", [y], [ca.sin(y) * ca.cos(y) + y ** 3])]
    library = kernels.KernelLibrary(["race"], ["race"], build)
    values = library.functions()["race"](x)[0]
    assert library.compiled and library.path.resolve() == final and calls == []
    np.testing.assert_allclose(values, expected, rtol=1e-13, atol=0)


def test_a_failing_compiler_falls_back_to_casadi_with_a_warning(tmp_path, monkeypatch):
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("KLAW_OCP_JIT", raising=False)
    monkeypatch.setenv("CC", "false")
    monkeypatch.setattr(kernels, "_compiler_state", {})
    calls = []
    library = _tiny_library(tmp_path, calls, tag="no-cc")
    with pytest.warns(RuntimeWarning, match="compiling solver kernels failed"):
        fns = library.functions()
    assert not library.compiled and calls == [True, False]
    np.testing.assert_array_equal(fns["tiny_square"]([1.0, -2.0, 0.5])[0], [1.0, 4.0, 0.25])


@requires_compiler
def test_a_walk_without_a_compiler_is_the_same_walk(monkeypatch):
    """KLAW_OCP_JIT=0 (or no compiler): every kernel and IPOPT's functions evaluated by CasADi,
    and the walk is the walk of the compiled kernels (so the compiled run must really use them)."""
    spec = walk_spec(load_config(ROOT / "configs" / "natural_walk.yaml"))
    spec = replace(spec, plans=spec.plans[:3])
    variants = (("multiple-shooting", "monitored"), ("plain-shooting", "monitored"), ("multiple-shooting", "tracking"))
    loaded, calls = [], Counter()
    load = kernels.KernelLibrary.load

    def spy_load(self):
        lib = load(self)
        loaded.append(self)
        return lib
    monkeypatch.setattr(kernels.KernelLibrary, "load", spy_load)
    for cls in (kernel_calls.CompiledFunction, kernel_calls.CasadiFunction):   # who evaluates the kernels' calls
        def counted(self, *args, _call=cls.__call__, _name=cls.__name__):
            calls[_name] += 1
            return _call(self, *args)
        monkeypatch.setattr(cls, "__call__", counted)
    results, used = {}, {}
    for jit in ("1", "0"):
        monkeypatch.setenv("KLAW_OCP_JIT", jit)
        integrator.subphase_kernels.cache_clear()
        ipopt_nlp.ipopt_solver.cache_clear()
        loaded.clear()
        calls.clear()
        with warnings.catch_warnings():
            warnings.simplefilter("error")   # no failed compile attempt, no warning
            results[jit] = [simulate_walk(replace(spec, method=m, stance=s)) for m, s in variants]
        used[jit] = ({lib.names[0]: (lib.compiled, lib.path) for lib in loaded}, dict(calls))
    integrator.subphase_kernels.cache_clear()
    ipopt_nlp.ipopt_solver.cache_clear()
    # both runs went through the same libraries: the four subphases' kernels and the tracking
    # stance's IPOPT functions ...
    libraries, c_calls = used["1"]
    assert {"stance_sim", "swing1_sim", "swing2_sim", "swing3_sim", "stance_20_nlp"} <= set(libraries)
    assert set(used["0"][0]) == set(libraries)
    # ... compiled and loaded from the cache in the first, every kernel call into the C library ...
    for name, (compiled, path) in libraries.items():
        assert compiled and path is not None and path.is_file() and path.parent == kernels.cache_dir(), name
    assert c_calls.get("CompiledFunction", 0) > 0 and c_calls.get("CasadiFunction", 0) == 0, c_calls
    # ... and evaluated by CasADi in the second, nothing compiled or loaded
    libraries, casadi_calls = used["0"]
    assert all(not compiled and path is None for compiled, path in libraries.values()), libraries
    assert casadi_calls.get("CasadiFunction", 0) > 0 and casadi_calls.get("CompiledFunction", 0) == 0, casadi_calls
    # The same walks. The kernels agree to round-off (1e-11, test_compiled_and_casadi_evaluation_agree;
    # bit for bit on x86-64 today, but a compiler may contract a*b+c into an FMA); the solvers then
    # stop at |residual| < 1e-10, so a round-off difference can at most end a solve an iteration
    # earlier or later, moving the solution by about tolerance x conditioning (~1e-9 relative).
    # 1e-7 leaves margin for that and still fails on any real difference (a wrong kernel moves the
    # torques by 1e-3 and more).
    assert len(results["1"]) == len(results["0"]) == len(variants)
    for (method, stance), compiled, plain in zip(variants, results["1"], results["0"]):
        where = f"{method}/{stance}"
        assert compiled.status == plain.status == "ok", where
        assert len(compiled.steps) == len(plain.steps) == len(spec.plans), where
        for k, (a, b) in enumerate(zip(compiled.steps, plain.steps)):
            names = [sp.name for sp in a.subphases]
            assert names == [sp.name for sp in b.subphases] == ["stance", "swing1", "swing2", "swing3"], (where, k)
            for sa, sb in zip(a.subphases, b.subphases):
                at = (where, k, sa.name)
                assert sa.success and sb.success and sa.parameters.keys() == sb.parameters.keys(), at
                for key, value in sa.parameters.items():
                    assert sb.parameters[key] == pytest.approx(value, rel=1e-7, abs=1e-9), (*at, key)
                np.testing.assert_allclose(sb.t, sa.t, rtol=1e-7, atol=1e-9, err_msg=str(at))
                np.testing.assert_allclose(sb.states, sa.states, rtol=1e-7, atol=1e-8, err_msg=str(at))


def test_condensed_newton_step_is_the_full_newton_step(problems):
    """Condensing is block elimination: its step must solve the whole multiple-shooting Jacobian."""
    from klaw_ocp.solvers.newton import CondensedNewton
    pb = problems["stance"]
    k = subphase_kernels(pb.spec, 4, pb.grid.size - 1)
    newton = CondensedNewton(k, 1e-10, 50)
    n, nx = k.intervals, pb.spec.nx
    free = [i for i, fixed in enumerate(pb.fixed) if not fixed]
    t, h = pb.grid[:-1], np.diff(pb.grid)
    rng = np.random.default_rng(3)
    X = _points(pb, k)[1:]
    X = np.vstack([X, X[-1]]) + 1e-3 * rng.standard_normal((n, nx))   # defects and final conditions off
    d, g, G = newton._residual(pb.x0, t, h, pb.guess, pb.context, X, 0.0)
    lin, _ = newton._linearise(pb.x0, t, h, pb.guess, pb.context, X, tuple(free), G)
    assert lin.T is not None           # the default grid keeps the dense transition products
    jac = np.zeros((n * nx + len(g), n * nx + len(free)))
    for i in range(n):
        jac[i * nx:(i + 1) * nx, i * nx:(i + 1) * nx] = np.eye(nx)
        if i:
            jac[i * nx:(i + 1) * nx, (i - 1) * nx:i * nx] = -lin.A[i]
        jac[i * nx:(i + 1) * nx, n * nx:] = -lin.B[i]
    jac[n * nx:, (n - 1) * nx:n * nx] = G
    full = np.linalg.solve(jac, -np.concatenate([d.ravel(), g]))
    # both forms of the defects' recursion: the dense products, and the loop of finer grids
    for form in (lin, replace(lin, T=None)):
        dX, du = newton._step(form, d, g)
        np.testing.assert_allclose(np.concatenate([dX.ravel(), du]), full, rtol=1e-8, atol=1e-12)


def test_chord_steps_reach_the_root_of_fresh_newton(problems):
    """A solve that starts from another problem's Jacobian (the chord) converges to the same root,
    to the tolerance, as one that evaluates its own."""
    from klaw_ocp.solvers.newton import CondensedNewton
    # swing2: Newton from its guess converges within one Jacobian there (swing1 from the virtual
    # leg's toe-off starts far enough off that even a fresh solve refreshes its Jacobian once)
    pb = problems["swing2"]
    FREE = [0, 2]                              # the knee torque's fall and mean (the actuator fixed)
    k = subphase_kernels(pb.spec, 4, pb.grid.size - 1)
    n = k.intervals
    t, h = pb.grid[:-1], np.diff(pb.grid)
    start = k.sim(pb.x0, t, h, pb.guess, pb.context)[0].reshape(n, -1)
    fresh = CondensedNewton(k, 1e-12, 50).solve(pb.x0, pb.grid, pb.guess, FREE, pb.context, start)
    chord = CondensedNewton(k, 1e-12, 50)
    nearby = pb.context * (1 + 1e-3)          # a neighbouring step's problem seeds the Jacobian
    chord.solve(pb.x0, pb.grid, pb.guess, FREE, nearby, start)
    again = chord.solve(pb.x0, pb.grid, pb.guess, FREE, pb.context, start)
    assert fresh.success and again.success and fresh.jacobians >= 1 and again.jacobians <= 1
    assert again.u[FREE] == pytest.approx(fresh.u[FREE], rel=1e-8)
    np.testing.assert_allclose(again.states, fresh.states, atol=1e-9)


@requires_compiler
def test_prepare_compiles_every_subphase_at_once(tmp_path, monkeypatch):
    """A walk's first solver call compiles the kernels of all four subphases in parallel threads
    (CasADi's symbolic work one thread at a time): the four compilers run at the same time, and
    each subphase ends up with its own compiled library in the cache, used by its kernels."""
    from klaw_ocp.control.stance_spec import stance_spec
    from klaw_ocp.control.swing_spec import swing_specs
    monkeypatch.setenv("KLAW_OCP_CACHE_DIR", str(tmp_path))
    specs = [stance_spec("momentum", False), *swing_specs("momentum").values()]
    # prefetch uses min(libraries, cores) threads: four "cores", so that the overlap shown below
    # does not depend on the machine the suite runs on
    monkeypatch.setattr(kernels.os, "cpu_count", lambda: len(specs))
    # every compiler call waits at a barrier until all four are running: if the compiles ran one
    # after another, the first would wait in vain (the timeout is only reached then)
    barrier, builds, run = threading.Barrier(len(specs), timeout=30), [], subprocess.run

    def compiler_run(cmd, *args, **kwargs):
        if "-o" not in cmd:                 # the compiler's --version, not a build
            return run(cmd, *args, **kwargs)
        try:
            barrier.wait()
            together = True
        except threading.BrokenBarrierError:
            together = False
        builds.append({"thread": threading.get_ident(), "together": together})
        return run(cmd, *args, **kwargs)

    monkeypatch.setattr(kernels.subprocess, "run", compiler_run)
    integrator.subphase_kernels.cache_clear()
    try:
        MultipleShootingSolver().prepare(specs)
        assert len(builds) == len(specs), "prepare compiled each subphase's library once"
        assert all(b["together"] for b in builds), "the four compilers ran at the same time"
        assert len({b["thread"] for b in builds}) == len(specs)
        libraries = list(tmp_path.rglob("*.so"))
        assert len(libraries) == len(specs) and not list(tmp_path.rglob(".build-*"))
        rng = np.random.default_rng(0)
        for spec in specs:
            k = subphase_kernels(spec, 4, 20)        # what prepare loaded (the per-process cache)
            assert k.library.compiled and k.library.path in libraries
            assert isinstance(k.final, kernel_calls.CompiledFunction), "the kernels call the compiled library"
            x, c = rng.uniform(-0.5, 0.5, spec.nx), rng.uniform(0.5, 1.0, spec.nc)
            np.testing.assert_allclose(k.final(x, c)[0], np.asarray(spec.final(x, c)).ravel(),
                                       rtol=1e-12, atol=1e-12, err_msg=spec.name)
        assert len({subphase_kernels(spec, 4, 20).library.path for spec in specs}) == len(specs)
        assert len(builds) == len(specs), "using the kernels after prepare compiles nothing more"
    finally:
        integrator.subphase_kernels.cache_clear()
