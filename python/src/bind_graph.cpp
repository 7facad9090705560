// The factor-graph engine from Python: keys' values, noise models, robust
// kernels, the library's own factors, factors written in Python, the graph,
// optimize() and marginal covariances.
//
// A factor written in Python is called by the optimizer through PythonFactor
// below, which takes the GIL for each call: optimize() and Marginals release
// it, and when OptimizerOptions.threads > 1 the worker threads that evaluate
// factors take it in turn (correct, but Python factors then run one at a time).
#include <optional>
#include <sstream>
#include <typeinfo>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>

#include "bindings.hpp"
#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/marginals.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::python {

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string shapeOf(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i) << (a.ndim() == 1 ? "," : "");
  s << ")";
  return s.str();
}

template <int N>
bool fixedVector(const Variable& v, py::object* out) {
  using V = Eigen::Matrix<double, N, 1>;
  if (v.type() != typeid(V)) return false;
  *out = py::cast(VecX(static_cast<const TypedVariable<V>&>(v).value()));
  return true;
}

// A variable's value as numpy: 4x4 for SE3, 3x3 for SO3, a 1-D array for vectors.
py::object toPython(const Variable& v, Key k) {
  const std::type_info& t = v.type();
  if (t == typeid(SE3)) return py::cast(static_cast<const TypedVariable<SE3>&>(v).value().matrix());
  if (t == typeid(SO3)) return py::cast(static_cast<const TypedVariable<SO3>&>(v).value().matrix());
  if (t == typeid(VecX)) return py::cast(static_cast<const TypedVariable<VecX>&>(v).value());
  py::object out;
  if (fixedVector<1>(v, &out) || fixedVector<2>(v, &out) || fixedVector<3>(v, &out) || fixedVector<4>(v, &out) ||
      fixedVector<5>(v, &out) || fixedVector<6>(v, &out))
    return out;
  throw py::type_error("variable " + keyToString(k) + " holds a type the Python module cannot show (" + t.name() +
                       ")");
}

// Inserts (or, with `assign`, replaces) a value given as numpy: a 4x4 rigid
// transform is an SE3, a 3x3 rotation an SO3, a 1-D array a vector.
void insertValue(Values& values, Key k, const py::handle& value, bool assign) {
  const Array a = Array::ensure(value);
  if (!a) throw py::type_error("value of " + keyToString(k) + ": expected a numpy array, got " +
                               std::string(py::str(py::type::of(value).attr("__name__"))));
  auto put = [&](const auto& x) { assign ? values.insertOrAssign(k, x) : values.insert(k, x); };
  const std::string what = "value of " + keyToString(k);
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4) {
    put(toSE3(Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(a.data()), what.c_str()));
  } else if (a.ndim() == 2 && a.shape(0) == 3 && a.shape(1) == 3) {
    put(toSO3(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.data()), what.c_str()));
  } else if (a.ndim() == 1 && a.shape(0) > 0) {
    put(VecX(Eigen::Map<const VecX>(a.data(), a.shape(0))));
  } else {
    throw py::value_error(what + ": expected a 4x4 transform (SE3), a 3x3 rotation (SO3) or a non-empty 1-D "
                          "vector, got shape " + shapeOf(a));
  }
}

py::object valueAt(const Values& values, Key k) {
  if (!values.exists(k)) throw py::key_error("no variable " + keyToString(k));
  return toPython(values.variable(k), k);
}

// Keeps a Python object alive while C++ holds it; released under the GIL,
// whichever thread drops the last reference.
struct PythonReference {
  py::object object;
  ~PythonReference() {
    py::gil_scoped_acquire gil;
    object = py::object();
  }
};

}  // namespace

/// The base of factors written in Python: a subclass implements
/// evaluate(values, jacobians). Called by the optimizer through evaluate()
/// below, from whichever thread evaluates it, under the GIL.
class PythonFactor : public Factor {
 public:
  PythonFactor(std::vector<Key> keys, NoiseModel::Ptr noise, RobustKernel::Ptr robust)
      : Factor(std::move(keys), std::move(noise), std::move(robust)) {}

  /// The Python method: returns the raw residual, or (residual, [J_0, ...])
  /// when `jacobians` is true (it may return the tuple either way).
  virtual py::object evaluatePython(const py::list& values, bool jacobians) const = 0;

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const final {
    py::gil_scoped_acquire gil;
    const std::vector<Key>& ks = keys();
    py::list xs(ks.size());
    for (std::size_t i = 0; i < ks.size(); ++i) xs[i] = toPython(*vars[i], ks[i]);
    bool want = false;
    for (std::size_t i = 0; jacobians && i < ks.size(); ++i) want = want || jacobians[i];
    const py::object out = evaluatePython(xs, want);

    py::object r = out, Js;
    if (py::isinstance<py::tuple>(out) && py::len(out) == 2 && py::isinstance<py::sequence>(out[py::int_(1)])) {
      r = out[py::int_(0)];
      Js = out[py::int_(1)];
    }
    const Array ra = Array::ensure(r);
    if (!ra || ra.size() != dim() || ra.ndim() > 2)
      throw py::value_error(describe() + ": evaluate() must return a residual of " + std::to_string(dim()) +
                            " numbers (the noise model's dimension), got " +
                            (ra ? "shape " + shapeOf(ra) : std::string(py::str(r))));
    std::copy(ra.data(), ra.data() + dim(), residual);
    if (!want) return;
    if (!Js || py::len(Js) != ks.size())
      throw py::value_error(describe() + ": evaluate(values, jacobians=True) must return (residual, [J_0, ..., J_" +
                            std::to_string(ks.size() - 1) + "]), one Jacobian per key");
    for (std::size_t i = 0; i < ks.size(); ++i) {
      if (!jacobians[i]) continue;
      const Array J = Array::ensure(Js[py::int_(i)]);
      const py::ssize_t rows = dim(), cols = vars[i]->dim();
      const bool ok = J && ((J.ndim() == 2 && J.shape(0) == rows && J.shape(1) == cols) ||
                            (rows == 1 && J.ndim() == 1 && J.shape(0) == cols));
      if (!ok)
        throw py::value_error(describe() + ": Jacobian " + std::to_string(i) + " (of " + keyToString(ks[i]) +
                              ") must be " + std::to_string(rows) + " x " + std::to_string(cols) + ", got " +
                              (J ? "shape " + shapeOf(J) : std::string("no array")));
      for (py::ssize_t c = 0; c < cols; ++c)
        for (py::ssize_t rr = 0; rr < rows; ++rr) jacobians[i][c * rows + rr] = J.data()[rr * cols + c];
    }
  }

  std::string describe() const override {
    py::gil_scoped_acquire gil;
    std::string name = "PythonFactor";
    const py::object self = py::cast(this, py::return_value_policy::reference);
    if (self) name = py::str(py::type::of(self).attr("__name__"));
    return name + " " + Factor::describe();
  }
};

namespace {

class PyPythonFactor final : public PythonFactor {
 public:
  using PythonFactor::PythonFactor;
  py::object evaluatePython(const py::list& values, bool jacobians) const override {
    PYBIND11_OVERRIDE_PURE_NAME(py::object, PythonFactor, "evaluate", evaluatePython, values, jacobians);
  }
};

std::string terminationName(Termination t) {
  switch (t) {
    case Termination::RelativeCostDecrease: return "relative_cost_decrease";
    case Termination::AbsoluteCost: return "absolute_cost";
    case Termination::SmallStep: return "small_step";
    case Termination::SmallGradient: return "small_gradient";
    case Termination::MaxIterations: return "max_iterations";
    case Termination::NoDecrease: return "no_decrease";
    case Termination::NotPositiveDefinite: return "not_positive_definite";
    case Termination::JacobianCheckFailed: return "jacobian_check_failed";
    case Termination::NonFiniteCost: return "non_finite_cost";
  }
  return "unknown";
}

using Algorithm = OptimizerOptions::Algorithm;
using LinearSolver = OptimizerOptions::LinearSolver;

Algorithm algorithmFromString(const std::string& s) {
  if (s == "levenberg_marquardt" || s == "lm") return Algorithm::LevenbergMarquardt;
  if (s == "gauss_newton" || s == "gn") return Algorithm::GaussNewton;
  throw py::value_error("algorithm: expected 'levenberg_marquardt' ('lm') or 'gauss_newton' ('gn'), got '" + s + "'");
}

LinearSolver linearSolverFromString(const std::string& s) {
  if (s == "auto") return LinearSolver::Auto;
  if (s == "sparse_cholesky") return LinearSolver::SparseCholesky;
  if (s == "schur_complement") return LinearSolver::SchurComplement;
  if (s == "streamed_schur_complement") return LinearSolver::StreamedSchurComplement;
  throw py::value_error("linear_solver: expected 'auto', 'sparse_cholesky', 'schur_complement' or "
                        "'streamed_schur_complement', got '" + s + "'");
}

std::string toString(LinearSolver s) {
  switch (s) {
    case LinearSolver::Auto: return "auto";
    case LinearSolver::SparseCholesky: return "sparse_cholesky";
    case LinearSolver::SchurComplement: return "schur_complement";
    case LinearSolver::StreamedSchurComplement: return "streamed_schur_complement";
  }
  return "auto";
}

// Options from an OptimizerOptions (or None) and keyword arguments naming its fields.
OptimizerOptions optionsFrom(const std::optional<OptimizerOptions>& given, const py::kwargs& kwargs) {
  OptimizerOptions o = given ? *given : OptimizerOptions{};
  if (kwargs.empty()) return o;
  py::object po = py::cast(o, py::return_value_policy::copy);
  for (const auto& item : kwargs) {
    const std::string name = py::str(item.first);
    if (name.empty() || name[0] == '_' || !py::hasattr(py::type::of(po), name.c_str()))
      throw py::type_error("optimize() got an unexpected keyword argument '" + name +
                           "' (the keywords are OptimizerOptions' fields)");
    po.attr(name.c_str()) = item.second;
  }
  return po.cast<OptimizerOptions>();
}

void bindValues(py::module_& m) {
  py::class_<Values>(m, "Values",
                     "The estimate of every variable, by key. Values are numpy arrays: a 4x4 rigid transform is an "
                     "SE3 variable, a 3x3 rotation an SO3 variable, a 1-D array a vector.")
      .def(py::init<>())
      .def(
          "insert", [](Values& v, Key k, const py::handle& x) { insertValue(v, k, x, false); }, py::arg("key"),
          py::arg("value"), "Adds a variable; ValueError when the key is already there.")
      .def(
          "update", [](Values& v, Key k, const py::handle& x) { insertValue(v, k, x, true); }, py::arg("key"),
          py::arg("value"), "Replaces a variable's value (same type), or inserts it.")
      .def("at", &valueAt, py::arg("key"), "The value of a key (a copy); KeyError when absent.")
      .def("__getitem__", &valueAt)
      .def("__setitem__", [](Values& v, Key k, const py::handle& x) { insertValue(v, k, x, true); })
      .def("__contains__", &Values::exists)
      .def("__len__", &Values::size)
      .def("keys", [](const Values& v) { return v.keys(); }, "Keys in insertion order.")
      .def(
          "dim", [](const Values& v, Key k) { return v.variable(k).dim(); }, py::arg("key"),
          "Tangent dimension of a variable (6 for SE3).")
      .def("copy", [](const Values& v) { return Values(v); })
      .def("__copy__", [](const Values& v) { return Values(v); })
      .def("__deepcopy__", [](const Values& v, const py::dict&) { return Values(v); })
      .def("__repr__", [](const Values& v) {
        std::string s = "Values(";
        for (std::size_t i = 0; i < v.keys().size(); ++i) s += (i ? ", " : "") + keyToString(v.keys()[i]);
        return s + ")";
      });
}

// Noise models and kernels are const objects in C++ (shared, never changed);
// pybind11's holders are of the mutable type, and Python offers no way to change them.
template <class T>
std::shared_ptr<T> mutablePtr(const std::shared_ptr<const T>& p) {
  return std::const_pointer_cast<T>(p);
}

void bindNoise(py::module_& m) {
  py::class_<NoiseModel, std::shared_ptr<NoiseModel>>(
      m, "NoiseModel",
      "Gaussian noise of a residual: whitening W with W^T W = Sigma^-1. ValueError for a covariance that is not "
      "symmetric positive definite.")
      .def_static(
          "from_covariance", [](const MatX& c) { return mutablePtr(NoiseModel::fromCovariance(c)); },
          py::arg("covariance"))
      .def_static(
          "from_information", [](const MatX& i) { return mutablePtr(NoiseModel::fromInformation(i)); },
          py::arg("information"))
      .def_static(
          "diagonal", [](const VecX& s) { return mutablePtr(NoiseModel::diagonal(s)); }, py::arg("sigmas"),
          "Per-axis standard deviations.")
      .def_static(
          "isotropic", [](int dim, double s) { return mutablePtr(NoiseModel::isotropic(dim, s)); }, py::arg("dim"),
          py::arg("sigma"))
      .def_property_readonly("dim", &NoiseModel::dim)
      .def_property_readonly("is_diagonal", &NoiseModel::isDiagonal)
      .def_property_readonly("covariance", &NoiseModel::covariance)
      .def_property_readonly("information", &NoiseModel::information)
      .def_property_readonly("sqrt_information", &NoiseModel::sqrtInformation)
      .def("whiten", &NoiseModel::whiten, py::arg("r"), "W r.");

  py::class_<RobustKernel, std::shared_ptr<RobustKernel>>(
      m, "RobustKernel", "rho(s) of the squared whitened residual s, applied by reweighting (huber, cauchy, tukey).")
      .def("rho", &RobustKernel::rho, py::arg("s"))
      .def("weight", &RobustKernel::weight, py::arg("s"), "rho'(s), the IRLS weight.")
      .def_property_readonly("name", &RobustKernel::name);
  m.def(
      "huber", [](double k) { return mutablePtr(huber(k)); }, py::arg("k"), "Quadratic inside k, linear outside.");
  m.def(
      "cauchy", [](double k) { return mutablePtr(cauchy(k)); }, py::arg("k"), "rho = k^2 log(1 + s / k^2).");
  m.def(
      "tukey", [](double k) { return mutablePtr(tukey(k)); }, py::arg("k"),
      "Redescending: residuals beyond k get zero weight.");
}

using NoisePtr = std::shared_ptr<NoiseModel>;
using KernelPtr = std::shared_ptr<RobustKernel>;

/// Factor and its kinds fgcal provides.
void bindFactorBase(py::module_& m) {
  py::class_<Factor, std::shared_ptr<Factor>>(m, "Factor",
                                              "A term of the cost: keys, a noise model, an optional robust kernel.")
      .def_property_readonly("keys", &Factor::keys)
      .def_property_readonly("dim", &Factor::dim, "Residual dimension.")
      .def_property_readonly("noise_model", [](const Factor& f) { return mutablePtr(f.noiseModelPtr()); })
      .def_property_readonly(
          "robust_kernel_name",
          [](const Factor& f) -> py::object {
            return f.robustKernel() ? py::cast(f.robustKernel()->name()) : py::none();
          },
          "The robust kernel's name, None without one.")
      .def(
          "set_robust_kernel", [](Factor& f, const KernelPtr& k) { f.setRobustKernel(k); }, py::arg("kernel"),
          "Sets (or with None removes) the robust kernel.")
      .def(
          "error",
          [](const Factor& f, const Values& v, bool jacobians) -> py::object {
            if (!jacobians) return py::cast(f.error(v));
            std::vector<MatX> J;
            VecX r = f.error(v, &J);
            return py::make_tuple(r, J);
          },
          py::arg("values"), py::arg("jacobians") = false,
          "Raw residual at `values`; with jacobians=True, (residual, [d r / d x_i])")
      .def("cost", &Factor::cost, py::arg("values"), "0.5 rho(|W r|^2).")
      .def("describe", &Factor::describe)
      .def("__repr__", [](const Factor& f) { return "<" + f.describe() + ">"; });

  py::class_<PriorFactorSE3, Factor, std::shared_ptr<PriorFactorSE3>>(
      m, "PriorFactorSE3", "Prior on an SE3 variable: r = Log(Z^-1 X), [w v].")
      .def(py::init([](Key k, const Mat4& Z, const NoisePtr& noise, const KernelPtr& robust) {
             return std::make_shared<PriorFactorSE3>(k, toSE3(Z, "measured"), noise, robust);
           }),
           py::arg("key"), py::arg("measured"), py::arg("noise_model"), py::arg("robust_kernel") = nullptr)
      .def_property_readonly("measured", [](const PriorFactorSE3& f) { return f.measured().matrix(); });

  py::class_<RelativePoseFactor, Factor, std::shared_ptr<RelativePoseFactor>>(
      m, "RelativePoseFactor", "Relative pose: measured Z ~ A^-1 B, r = Log(Z^-1 A^-1 B), [w v].")
      .def(py::init([](Key a, Key b, const Mat4& Z, const NoisePtr& noise, const KernelPtr& robust) {
             return std::make_shared<RelativePoseFactor>(a, b, toSE3(Z, "measured"), noise, robust);
           }),
           py::arg("a"), py::arg("b"), py::arg("measured"), py::arg("noise_model"),
           py::arg("robust_kernel") = nullptr)
      .def_property_readonly("measured", [](const RelativePoseFactor& f) { return f.measured().matrix(); });

  py::class_<KinematicFactor, Factor, std::shared_ptr<KinematicFactor>>(
      m, "KinematicFactor",
      "The board pose L tied to the forward kinematics T_base_link and the board mount M: "
      "r = Log((T_base_link M)^-1 L).")
      .def(py::init([](Key board, Key mount, const Mat4& T_base_link, const NoisePtr& noise, const KernelPtr& robust) {
             return std::make_shared<KinematicFactor>(board, mount, toSE3(T_base_link, "T_base_link"), noise, robust);
           }),
           py::arg("board"), py::arg("mount"), py::arg("T_base_link"), py::arg("noise_model"),
           py::arg("robust_kernel") = nullptr)
      .def_property_readonly("link_pose", [](const KinematicFactor& f) { return f.linkPose().matrix(); })
      .def_static(
          "marker_covariance",
          [](const Mat6& link_covariance, const Mat4& T_link_marker) {
            return KinematicFactor::markerCovariance(link_covariance, toSE3(T_link_marker, "T_link_marker"));
          },
          py::arg("link_covariance"), py::arg("T_link_marker"),
          "The residual's covariance from that of T_base_link's right perturbation.");
}

/// A factor written in Python, and the Jacobian check.
void bindPythonFactor(py::module_& m) {
  py::class_<PythonFactor, Factor, PyPythonFactor, std::shared_ptr<PythonFactor>>(m, "PythonFactor", R"doc(
A factor written in Python. Subclass it, call PythonFactor.__init__(self, keys,
noise_model, robust_kernel=None), and implement

    def evaluate(self, values, jacobians):
        # values: one numpy array per key (4x4 for SE3, 3x3 for SO3, 1-D vectors)
        # returns the raw residual (dim numbers), and when jacobians is True
        # (residual, [J_0, J_1, ...]) with J_i = d r / d x_i, dim x (tangent dim
        # of key i), under the right perturbation ([w v] for SE3).

Whitening by the noise model and the robust kernel are the engine's business.
Check the Jacobians with check_factor_jacobians(factor, values).

Slower than the library's own factors: every evaluation calls into Python
under the GIL (tens of microseconds, against well under one for a C++
factor), so graphs of many Python factors spend their time there, and with
OptimizerOptions.threads > 1 Python factors still run one at a time.
)doc")
      .def(py::init<std::vector<Key>, const NoisePtr&, const KernelPtr&>(), py::arg("keys"), py::arg("noise_model"),
           py::arg("robust_kernel") = nullptr)
      .def("evaluate", &PythonFactor::evaluatePython, py::arg("values"), py::arg("jacobians"));

  py::class_<JacobianMismatch>(m, "JacobianMismatch")
      .def_readonly("key_position", &JacobianMismatch::key_position)
      .def_readonly("key", &JacobianMismatch::key)
      .def_readonly("max_abs_error", &JacobianMismatch::max_abs_error)
      .def_readonly("max_abs_entry", &JacobianMismatch::max_abs_entry)
      .def_readonly("message", &JacobianMismatch::message)
      .def("__repr__", [](const JacobianMismatch& j) { return "<JacobianMismatch: " + j.message + ">"; });
  m.def("check_factor_jacobians", &checkFactorJacobians, py::arg("factor"), py::arg("values"), py::arg("step") = 1e-6,
        py::arg("tolerance") = 1e-5,
        "Compares every Jacobian block of a factor with central differences through each variable's retraction; "
        "returns the blocks that differ by more than tolerance (relative to 1 + |entry|): empty when all agree.");
}

void bindFactors(py::module_& m) {
  bindFactorBase(m);
  bindPythonFactor(m);
}

/// The factor graph and the optimizer's options.
void bindGraph(py::module_& m) {
  py::class_<FactorGraph>(m, "FactorGraph", "The list of factors. Do not change it while optimize() runs on it.")
      .def(py::init<>())
      .def(
          "add",
          [](FactorGraph& g, const py::object& f) {
            auto factor = f.cast<std::shared_ptr<Factor>>();
            // The graph keeps a Python factor's Python half alive too (pybind11's
            // holder alone would keep only the C++ half).
            if (dynamic_cast<PythonFactor*>(factor.get()))
              factor = std::shared_ptr<Factor>(std::make_shared<PythonReference>(PythonReference{f}), factor.get());
            g.add(std::move(factor));
          },
          py::arg("factor"))
      .def("__len__", &FactorGraph::size)
      .def("__getitem__",
           [](const FactorGraph& g, std::size_t i) {
             if (i >= g.size()) throw py::index_error("factor index out of range");
             return g.at(i);
           })
      .def("cost", &FactorGraph::cost, py::arg("values"), "Sum of 0.5 rho(|W r|^2).");

  py::class_<OptimizerOptions>(m, "OptimizerOptions",
                               "Options of optimize(); also accepted as its keyword arguments.")
      .def(py::init<>())
      .def_property(
          "algorithm",
          [](const OptimizerOptions& o) {
            return o.algorithm == Algorithm::GaussNewton ? "gauss_newton" : "levenberg_marquardt";
          },
          [](OptimizerOptions& o, const std::string& s) { o.algorithm = algorithmFromString(s); },
          "'levenberg_marquardt' (default, or 'lm') or 'gauss_newton' ('gn').")
      .def_property(
          "linear_solver", [](const OptimizerOptions& o) { return toString(o.linear_solver); },
          [](OptimizerOptions& o, const std::string& s) { o.linear_solver = linearSolverFromString(s); },
          "'auto', 'sparse_cholesky' or 'schur_complement'.")
      .def_readwrite("max_iterations", &OptimizerOptions::max_iterations)
      .def_readwrite("relative_cost_tolerance", &OptimizerOptions::relative_cost_tolerance)
      .def_readwrite("absolute_cost_tolerance", &OptimizerOptions::absolute_cost_tolerance)
      .def_readwrite("step_tolerance", &OptimizerOptions::step_tolerance)
      .def_readwrite("gradient_tolerance", &OptimizerOptions::gradient_tolerance)
      .def_readwrite("initial_lambda", &OptimizerOptions::initial_lambda)
      .def_readwrite("min_diagonal", &OptimizerOptions::min_diagonal)
      .def_readwrite("max_diagonal", &OptimizerOptions::max_diagonal)
      .def_readwrite("check_jacobians", &OptimizerOptions::check_jacobians)
      .def_readwrite("jacobian_check_tolerance", &OptimizerOptions::jacobian_check_tolerance)
      .def_readwrite("fixed_keys", &OptimizerOptions::fixed_keys, "Keys held at their initial value (assign a list).")
      .def_readwrite("threads", &OptimizerOptions::threads,
                     "Threads for large graphs (0: every core). Python factors run one at a time under the GIL.")
      .def_readwrite("callback", &OptimizerOptions::callback,
                     "Called with an IterationReport after every iteration (under the GIL).");
}

/// The optimizer's reports and result, optimize() and the marginals.
void bindSolver(py::module_& m) {
  py::class_<IterationReport>(m, "IterationReport")
      .def_readonly("iteration", &IterationReport::iteration)
      .def_readonly("cost", &IterationReport::cost)
      .def_readonly("cost_change", &IterationReport::cost_change)
      .def_readonly("step_norm", &IterationReport::step_norm)
      .def_readonly("lambda_", &IterationReport::lambda)
      .def_readonly("accepted", &IterationReport::accepted)
      .def_readonly("linearize_seconds", &IterationReport::linearize_seconds)
      .def_readonly("solve_seconds", &IterationReport::solve_seconds)
      .def_readonly("total_seconds", &IterationReport::total_seconds);

  py::class_<OptimizerResult>(m, "OptimizerResult")
      .def_readonly("values", &OptimizerResult::values)
      .def_property_readonly("termination", [](const OptimizerResult& r) { return terminationName(r.termination); })
      .def_readonly("converged", &OptimizerResult::converged)
      .def_readonly("message", &OptimizerResult::message)
      .def_readonly("initial_cost", &OptimizerResult::initial_cost)
      .def_readonly("final_cost", &OptimizerResult::final_cost)
      .def_readonly("iterations", &OptimizerResult::iterations)
      .def_readonly("reports", &OptimizerResult::reports)
      .def_property_readonly(
          "cost_history",
          [](const OptimizerResult& r) {
            std::vector<double> c{r.initial_cost};
            for (const auto& it : r.reports) c.push_back(it.cost);
            return c;
          },
          "The initial cost, then the cost after every iteration.")
      .def_readonly("linearize_seconds", &OptimizerResult::linearize_seconds)
      .def_readonly("analyze_seconds", &OptimizerResult::analyze_seconds)
      .def_readonly("solve_seconds", &OptimizerResult::solve_seconds)
      .def_readonly("total_seconds", &OptimizerResult::total_seconds)
      .def_readonly("linear_solver", &OptimizerResult::linear_solver)
      .def_readonly("degenerate_keys", &OptimizerResult::degenerate_keys)
      .def("__repr__", [](const OptimizerResult& r) {
        return "<OptimizerResult: " + std::string(r.converged ? "converged" : "not converged") + " (" + r.message +
               ") after " + std::to_string(r.iterations) + " iterations, cost " + std::to_string(r.final_cost) + ">";
      });

  m.def(
      "optimize",
      [](const FactorGraph& graph, const Values& initial, const std::optional<OptimizerOptions>& options,
         const py::kwargs& kwargs) {
        const OptimizerOptions o = optionsFrom(options, kwargs);
        py::gil_scoped_release release;
        return optimize(graph, initial, o);
      },
      py::arg("graph"), py::arg("initial"), py::arg("options") = py::none(),
      "Minimizes 0.5 sum rho(|W r|^2) from `initial` (Levenberg-Marquardt by default): optimize(graph, values, "
      "algorithm='gauss_newton', max_iterations=20), or with an OptimizerOptions. Releases the GIL while it runs.");

  py::class_<Marginals>(m, "Marginals",
                        "Marginal covariances at an estimate, in each variable's tangent space ([w v] for SE3).")
      .def(py::init([](const FactorGraph& graph, const Values& estimate, const std::vector<Key>& fixed) {
             py::gil_scoped_release release;
             return std::make_unique<Marginals>(graph, estimate, fixed);
           }),
           py::arg("graph"), py::arg("estimate"), py::arg("fixed") = std::vector<Key>{}, py::keep_alive<1, 2>())
      .def("covariance", &Marginals::covariance, py::arg("key"))
      .def("joint_covariance", &Marginals::jointCovariance, py::arg("keys"));
}

void bindGraphAndSolver(py::module_& m) {
  bindGraph(m);
  bindSolver(m);
}

}  // namespace

void bindGraph(py::module_& m) {
  bindValues(m);
  bindNoise(m);
  bindFactors(m);
  bindGraphAndSolver(m);
}

}  // namespace fgcal::python
