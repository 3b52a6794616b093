//! `somnurbs._native`: the Python face of somnurbs' Chapter 6 problems (issue 39). The problems
//! come from [`somnurbs::families::suite::load`], the code path of `somnurbs run`, and
//! `f` calls the same compiled fitness, so values are bit for bit the CLI's on the same machine.
//! Evaluation reads a C-contiguous float64 array in place and runs with the GIL released.

use numpy::{PyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyError, PyNotImplementedError, PyRuntimeError, PyTypeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use somnurbs::data::DataError;
use somnurbs::families::suite::{self, Fitness, RequestError, Suite, SuiteProblem};
use somnurbs::optim::ExactOptions;
use somnurbs::optim::ExactResult;
use somnurbs::spline::KnotRule;
use std::sync::{Arc, OnceLock};

/// What every problem of one `problems()` call shares.
struct Meta {
    spec: String,
    profile: Option<String>,
    reading: String,
    box_label: String,
    exact: ExactOptions,
}

/// One control-net problem: minimise Eq. 6.2 over the control points.
#[pyclass(frozen, module = "somnurbs", name = "Problem")]
struct PyProblem {
    p: Arc<SuiteProblem>,
    meta: Arc<Meta>,
    /// The exact optimum in the spec's box and in the data-range box, once asked for.
    exact_spec: OnceLock<ExactResult>,
    exact_wide: OnceLock<ExactResult>,
}

fn err(e: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(format!("{e:#}"))
}

fn array<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A shape as Python writes it: `()`, `(3,)`, `(2, 3)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// `x` as a float64 array: a C-contiguous float64 array is read in place; other real arrays
/// (integers, float32, strided, Fortran order, big-endian), lists and tuples go through
/// `numpy.ascontiguousarray` (one copy). Complex and bool arrays are refused (a complex value's
/// imaginary part would be dropped, a bool is no coordinate), and so is anything that is not an
/// array of numbers.
fn float_array<'py>(x: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    if let Ok(a) = x.extract::<PyReadonlyArrayDyn<'py, f64>>() {
        if a.is_c_contiguous() {
            return Ok(a);
        }
    }
    let np = x.py().import("numpy")?;
    let arr = np.getattr("asarray")?.call1((x,)).map_err(|_| not_real(x))?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    match kind.as_str() {
        "f" | "i" | "u" => {}
        "c" => return Err(PyValueError::new_err("x is complex; f takes real coordinates")),
        "b" => return Err(PyValueError::new_err("x is boolean; f takes real coordinates")),
        _ => return Err(not_real(x)),
    }
    let kw = PyDict::new(x.py());
    kw.set_item("dtype", "float64")?;
    let c = np.getattr("ascontiguousarray")?.call((arr,), Some(&kw))?;
    c.extract::<PyReadonlyArrayDyn<'py, f64>>()
}

fn not_real(x: &Bound<'_, PyAny>) -> PyErr {
    let ty = x.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    PyTypeError::new_err(format!(
        "x must be a real array of shape (dimension,) or (n, dimension), got {ty}"
    ))
}

/// Rows evaluated between two looks at Python's signals (Ctrl-C): a few milliseconds of work.
const ROWS_PER_CHECK: usize = 2048;

/// f of every row, the GIL released; Ctrl-C (any pending signal) stops the batch between chunks.
fn batch(
    py: Python<'_>,
    problem: &dyn somnurbs::optim::Problem,
    data: &[f64],
) -> PyResult<Vec<f64>> {
    let d = problem.dim();
    let mut out = Vec::with_capacity(data.len() / d.max(1));
    for chunk in data.chunks(ROWS_PER_CHECK * d) {
        py.detach(|| out.extend(chunk.chunks_exact(d).map(|row| problem.fitness(row))));
        py.check_signals()?;
    }
    Ok(out)
}

/// A ValueError for the first row whose value is not finite: a NaN or infinite coordinate, or
/// coordinates so large that the distances overflow.
fn check_finite(name: &str, values: &[f64], data: &[f64], d: usize) -> PyResult<()> {
    let Some(i) = values.iter().position(|v| !v.is_finite()) else { return Ok(()) };
    let row = &data[i * d..(i + 1) * d];
    let at = if values.len() == 1 { String::new() } else { format!(" row {i}") };
    Err(PyValueError::new_err(match row.iter().position(|v| !v.is_finite()) {
        Some(j) => {
            let v = if row[j].is_nan() {
                "nan"
            } else if row[j] > 0.0 {
                "inf"
            } else {
                "-inf"
            };
            format!("{name}: x{at} has {v} at index {j}; f takes finite coordinates")
        }
        None => {
            let big = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            format!("{name}: f{at} overflows (|x| up to {big:e}); coordinates that large are no surface")
        }
    }))
}

/// A loader's error as Python's: an unknown spec or profile is a KeyError naming what is offered,
/// a missing spec or data file a FileNotFoundError, any other refused setting a ValueError.
fn load_error(e: anyhow::Error) -> PyErr {
    let msg = format!("{e:#}");
    if let Some(r) = e.downcast_ref::<RequestError>() {
        return match r {
            RequestError::SpecFile { .. } => PyFileNotFoundError::new_err(msg),
            _ => PyKeyError::new_err(msg),
        };
    }
    if e.chain().any(|c| matches!(c.downcast_ref::<DataError>(), Some(DataError::Missing { .. }))) {
        return PyFileNotFoundError::new_err(msg);
    }
    PyValueError::new_err(msg)
}

impl PyProblem {
    /// The kept result of a box ("spec" or "data") and whether it is the data-range box.
    fn exact_cell(&self, which: &str) -> PyResult<(&OnceLock<ExactResult>, bool)> {
        match which {
            "spec" => Ok((&self.exact_spec, false)),
            "data" => Ok((&self.exact_wide, true)),
            _ => Err(PyValueError::new_err(format!("box must be 'spec' or 'data', got {which:?}"))),
        }
    }

    fn exact_result(&self, py: Python<'_>, which: &str) -> PyResult<&ExactResult> {
        let (cell, data_range) = self.exact_cell(which)?;
        if let Some(r) = cell.get() {
            return Ok(r);
        }
        if !self.has_exact_solver() {
            return Err(PyNotImplementedError::new_err(format!(
                "{}: seed 001's open surfaces have no exact solver",
                self.p.name
            )));
        }
        let opts = self.meta.exact.clone();
        let p = &self.p;
        let r = py.detach(|| p.exact(data_range, &opts)).map_err(err)?;
        Ok(cell.get_or_init(|| r))
    }
}

#[pymethods]
impl PyProblem {
    /// The fitness (Eq. 6.2, the sum of distances between the two-view grid and the surfaces):
    /// a float for one point (1-D array of `dimension`), an array of n floats for a 2-D array of
    /// n rows. Not clamped to any box; the GIL is released while it runs.
    fn f<'py>(&self, py: Python<'py>, x: &Bound<'py, PyAny>) -> PyResult<Py<PyAny>> {
        let a = float_array(x)?;
        let problem = self.p.problem();
        let d = problem.dim();
        let shape = a.shape().to_vec();
        let data = a.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))?;
        match shape.as_slice() {
            [n] if *n == d => {
                let v = py.detach(|| problem.fitness(data));
                check_finite(&self.p.name, &[v], data, d)?;
                Ok(v.into_pyobject(py)?.into_any().unbind())
            }
            [_, n] if *n == d => {
                let out = batch(py, problem, data)?;
                check_finite(&self.p.name, &out, data, d)?;
                Ok(PyArray1::from_vec(py, out).into_any().unbind())
            }
            _ => Err(PyValueError::new_err(format!(
                "{}: x must have shape ({d},) or (n, {d}), got {}",
                self.p.name,
                shape_text(&shape)
            ))),
        }
    }

    /// The IOHprofiler function name, `<dataset>_<grid>_<net>_<parameterisation>`.
    #[getter]
    fn name(&self) -> &str {
        &self.p.name
    }
    /// The IOHprofiler function id: the problem's place in the spec's order, as `somnurbs run`'s
    /// `ioh/` numbers it and `ioh_adapter` logs it.
    #[getter]
    fn function_id(&self) -> u32 {
        self.p.function_id
    }
    #[getter]
    fn dataset(&self) -> &str {
        &self.p.dataset
    }
    /// The SOM map's size, e.g. "20x20".
    #[getter]
    fn grid(&self) -> String {
        self.p.grid.to_string()
    }
    /// The control net's size, e.g. "18x18".
    #[getter]
    fn net(&self) -> String {
        self.p.net.to_string()
    }
    #[getter]
    fn parameterisation(&self) -> &str {
        self.p.param.name()
    }
    /// The knot reading of B (docs/readings.md): "eq2_10" or "nurbs_book".
    #[getter]
    fn reading(&self) -> &str {
        &self.meta.reading
    }
    #[getter]
    fn spec(&self) -> &str {
        &self.meta.spec
    }
    #[getter]
    fn profile(&self) -> Option<&str> {
        self.meta.profile.as_deref()
    }
    /// The spec's search box in words: "B+-5e-6" (Table 6.1) or "cover+0e0" (data and B).
    #[getter]
    fn box_label(&self) -> &str {
        &self.meta.box_label
    }
    #[getter]
    fn dimension(&self) -> usize {
        self.p.problem().dim()
    }
    /// Approach B's control points: the thesis' start.
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array(py, self.p.problem().initial_point())
    }
    /// B's error, f(x0).
    #[getter]
    fn b(&self) -> f64 {
        self.p.problem().fitness(self.p.problem().initial_point())
    }
    /// The spec's search box (the one `somnurbs run` searches), lower bounds.
    #[getter]
    fn lower<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array(py, self.p.problem().bounds().0)
    }
    #[getter]
    fn upper<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array(py, self.p.problem().bounds().1)
    }
    /// The data-range box (the data and B's control points per axis), lower bounds.
    #[getter]
    fn lower_data<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array(py, self.p.data_box().0)
    }
    #[getter]
    fn upper_data<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array(py, self.p.data_box().1)
    }

    /// The certified optimum in a box ("spec" or "data"), computed on first call and kept: a dict
    /// with `interval` = (`lower_bound`, `f`), the certificate (min f over the box lies in it),
    /// `f` (the value at `x`, the best point found: an upper bound), `lower_bound` (proven: no
    /// point of the box is below it), `gap` = f - lower_bound, `converged` (the gap reached the
    /// spec's `exact_tol` relative to f), `iterations` and `x`.
    #[pyo3(signature = (r#box = "spec"))]
    fn exact<'py>(&self, py: Python<'py>, r#box: &str) -> PyResult<Bound<'py, PyDict>> {
        let r = self.exact_result(py, r#box)?;
        let d = PyDict::new(py);
        d.set_item("interval", (r.lower_bound, r.f))?;
        d.set_item("f", r.f)?;
        d.set_item("lower_bound", r.lower_bound)?;
        d.set_item("gap", r.gap)?;
        d.set_item("converged", r.converged)?;
        d.set_item("iterations", r.iterations)?;
        d.set_item("x", array(py, &r.x))?;
        Ok(d)
    }

    /// Whether `exact()` can certify an optimum (Chapter 6's double nets: yes; seed 001's open
    /// surfaces: no).
    #[getter]
    fn has_exact_solver(&self) -> bool {
        matches!(self.p.fitness, Fitness::ControlNet { .. })
    }

    /// Whether `exact(box)` has been computed already (no computation).
    #[pyo3(signature = (r#box = "spec"))]
    fn has_exact(&self, r#box: &str) -> PyResult<bool> {
        Ok(self.exact_cell(r#box)?.0.get().is_some())
    }

    /// Everything that identifies the problem, as `compare` checks it.
    fn metadata<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("name", &self.p.name)?;
        d.set_item("function_id", self.p.function_id)?;
        d.set_item("dataset", &self.p.dataset)?;
        d.set_item("grid", self.grid())?;
        d.set_item("net", self.net())?;
        d.set_item("parameterisation", self.p.param.name())?;
        d.set_item("reading", &self.meta.reading)?;
        d.set_item("spec", &self.meta.spec)?;
        d.set_item("profile", self.meta.profile.as_deref())?;
        d.set_item("box", &self.meta.box_label)?;
        d.set_item("dimension", self.dimension())?;
        d.set_item("b", self.b())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "<somnurbs.Problem {} dim {} ({}{}, reading {}, box {})>",
            self.p.name,
            self.dimension(),
            self.meta.spec,
            self.meta.profile.as_deref().map(|p| format!(" --profile {p}")).unwrap_or_default(),
            self.meta.reading,
            self.meta.box_label
        )
    }
}

/// Every control-net problem of a Chapter 6 spec (a shipped name such as "ch6_same", or a TOML
/// path), under a profile ("quick") and a knot reading ("eq2_10", "nurbs_book"; None: the
/// spec's); `set` takes further `KEY=VALUE` settings as `somnurbs run --set`. A shipped name is
/// read from `experiments/<name>.toml` in the working folder when there is one (a clone's), else
/// from the copy inside the package. Data files come from `data_dir`, else `SOMNURBS_DATA`, else
/// `data/` in the working folder. An unknown spec or profile raises KeyError naming what is
/// offered, an unknown reading or setting ValueError, a missing file FileNotFoundError.
#[pyfunction]
#[pyo3(signature = (spec = "ch6_same", profile = None, reading = None, set = None, data_dir = None))]
fn problems(
    py: Python<'_>,
    spec: &str,
    profile: Option<&str>,
    reading: Option<&str>,
    set: Option<Vec<String>>,
    data_dir: Option<std::path::PathBuf>,
) -> PyResult<Vec<PyProblem>> {
    let mut set = set.unwrap_or_default();
    if let Some(r) = reading {
        if !KnotRule::ALL.iter().any(|k| k.name() == r) {
            let offered: Vec<&str> = KnotRule::ALL.iter().map(|k| k.name()).collect();
            return Err(PyValueError::new_err(format!(
                "reading={r:?}: no such knot reading (offered: {})",
                offered.join(", ")
            )));
        }
        set.push(format!("optimise.knots={r}"));
    }
    let data_dir = data_dir
        .or_else(|| std::env::var_os("SOMNURBS_DATA").filter(|v| !v.is_empty()).map(Into::into))
        .unwrap_or_else(|| "data".into());
    let work = tempfile::tempdir().map_err(err)?;
    let s: Suite = py
        .detach(|| suite::load(spec, profile, &set, Some(&data_dir), work.path()))
        .map_err(load_error)?;
    let meta = Arc::new(Meta {
        spec: s.spec_name,
        profile: s.profile,
        reading: s.reading,
        box_label: s.box_label,
        exact: s.exact,
    });
    Ok(s.problems
        .into_iter()
        .map(|p| PyProblem {
            p: Arc::new(p),
            meta: meta.clone(),
            exact_spec: OnceLock::new(),
            exact_wide: OnceLock::new(),
        })
        .collect())
}

/// Send the library's notes and progress lines (a map recomputed, cells done) to the Python
/// logger `somnurbs` at INFO (WARNING for warnings), so that `logging` can show, silence or
/// redirect them; nothing goes to file descriptor 2.
fn log_notices(py: Python<'_>) -> PyResult<()> {
    let logger: Py<PyAny> =
        py.import("logging")?.getattr("getLogger")?.call1(("somnurbs",))?.unbind();
    somnurbs::notice::set_sink(Some(Box::new(move |line: &str| {
        Python::attach(|py| {
            let level = if line.contains("warning") { "warning" } else { "info" };
            let text = line.strip_prefix("somnurbs: ").unwrap_or(line);
            if let Err(e) = logger.call_method1(py, level, ("%s", text)) {
                e.write_unraisable(py, None);
            }
        })
    })));
    Ok(())
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    log_notices(m.py())?;
    let specs: Vec<&str> = suite::SHIPPED.iter().map(|(n, _)| *n).collect();
    m.add("SPECS", pyo3::types::PyTuple::new(m.py(), specs)?)?;
    m.add_function(wrap_pyfunction!(problems, m)?)?;
    m.add_class::<PyProblem>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
