// A user-defined basis phi (eq. 19) of N functions of the error state x = [e1; e2] (2n) and the
// desired joint position qd (n), compiled once from a postfix program and evaluated with its exact
// Jacobians d phi / d x (N x 2n) and d phi / d qd (N x n) by forward-mode differentiation.
//
// The variables are z = [x; qd] (3n); a term in the joint angles q is written through them
// (q = qd - e1, python/adparm/bases.py substitutes it). The program is a flat sequence of
// instructions run on a stack whose every slot holds a value and its gradient:
//   constant a          push a
//   variable i          push z_i (0 <= i < 3n)
//   add subtract multiply
//                       pop b, pop a, push a + b, a - b, a b (product rule)
//   negate              -a
//   power a             b^a: an integer |a| <= 64 by repeated products (b^2 = b b exactly), a = 1/2
//                       by std::sqrt, any other real a by std::pow
//   sin cos tan exp log sqrt tanh
//                       the function of the top value, its derivative by the chain rule
//   store               pop the single value left into the next phi_k (the stack must then be
//                       empty)
// Each function differentiates only with respect to the variables it reads (its local gradient
// is as long as that list), so a quadratic monomial costs the same whatever n. A function that is
// a monomial c prod z_i^p_i (the quadratic and polynomial families) skips the stack: the same
// products in the same order, so the same numbers. A function (sin ... tanh) of an argument whose
// program occurred before (cos q2 in several terms) is computed once per evaluation.
//
// All buffers are sized at construction (ExpressionBasis) or by workspace() (Workspace); evaluate
// allocates nothing. The basis is immutable once built and may be shared between threads, each
// with its own Workspace; the evaluate overloads without a Workspace use the basis' own and are
// for one thread at a time.
//
// Interface as the fixed-size bases of basis.hpp, with dynamic sizes:
//   size(), state_dim() = 2n, joints() = n,
//   evaluate(x, desired, phi, jacobian, desired_rate)   desired_rate = (d phi / d qd) dqd
//   evaluate(x, desired, terms, phi, jacobian, desired_rate)   (terms unused)
// A program that cannot run (unknown opcode, variable index out of range, stack underflow, a store
// that does not leave exactly one value, values left unstored, no function) and wrong argument
// sizes throw std::invalid_argument naming the instruction or the argument.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "adparm/types.hpp"

namespace adparm {

enum class ExpressionOp : int {
  constant = 0,
  variable = 1,
  add = 2,
  subtract = 3,
  multiply = 4,
  negate = 5,
  power = 6,
  sin = 7,
  cos = 8,
  tan = 9,
  exp = 10,
  log = 11,
  sqrt = 12,
  tanh = 13,
  store = 14,
};

// One instruction: its argument is the constant, the variable index (an integer value) or the
// exponent; the other operations ignore it.
struct ExpressionInstruction {
  ExpressionOp op = ExpressionOp::constant;
  double argument = 0.0;
};

// A program as the settings carry it (Settings::basis_program): one argument per opcode.
struct ExpressionProgram {
  std::vector<int> opcodes;
  std::vector<double> arguments;
};

// The instructions of `program`; `name` names the settings field in the errors.
inline std::vector<ExpressionInstruction> expression_instructions(const ExpressionProgram& program,
                                                                  const std::string& name) {
  if (program.opcodes.size() != program.arguments.size())
    throw std::invalid_argument(name + ".arguments: expected one per opcode (" +
                                std::to_string(program.opcodes.size()) + "), got " +
                                std::to_string(program.arguments.size()));
  std::vector<ExpressionInstruction> out(program.opcodes.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = {static_cast<ExpressionOp>(program.opcodes[i]), program.arguments[i]};
  return out;
}

class ExpressionBasis {
 public:
  using Vector = Eigen::VectorXd;
  using Jacobian = Eigen::MatrixXd;  // d phi / d x (N x 2n)

  // The evolving buffers of one evaluation: values (stack depth) and gradients (longest local
  // variable list x stack depth, one column per stack slot).
  struct Workspace {
    Eigen::VectorXd values;
    Eigen::MatrixXd gradients;
    Eigen::VectorXd cache;  // value and derivative of each repeated function (cos q2 ...)
  };

  ExpressionBasis(int joints, const std::vector<ExpressionInstruction>& program) : joints_(joints) {
    if (joints < 1)
      throw std::invalid_argument("joints: must be >= 1, got " + std::to_string(joints));
    compile(program);
    workspace_ = workspace();
    find_pairs();
  }

  // A basis of pairs: every function phi_k = c_k x_a x_b (a = b allowed: x_a^2) of the error state
  // alone, as the quadratic family. Its row of d phi / d e2 (e2 = x[n:]) has at most two terms:
  //   d phi_k / d e2 z = coefficient[k] sum_t x[term_x[2k + t]] z[term_z[2k + t]]  (t = 0, 1),
  // term_z an e2 index 0 ... n - 1, or -1: no term (phi_k = c x_a x_b: terms (x_b, a - n) and
  // (x_a, b - n); x_a^2: (x_a, a - n) twice). Empty for any other basis.
  struct Pairs {
    std::vector<int> term_x, term_z;
    std::vector<double> coefficient;
    bool empty() const { return coefficient.empty(); }
  };
  const Pairs& pairs() const { return pairs_; }

  int size() const { return static_cast<int>(functions_.size()); }
  int joints() const { return joints_; }
  int state_dim() const { return 2 * joints_; }
  int variables() const { return 3 * joints_; }  // z = [x; qd]
  int stack_depth() const { return depth_; }
  int instructions() const { return static_cast<int>(code_.size()); }

  Workspace workspace() const {
    Workspace w;
    w.values = Eigen::VectorXd::Zero(depth_);
    w.gradients = Eigen::MatrixXd::Zero(std::max(max_locals_, 1), depth_);
    w.cache = Eigen::VectorXd::Zero(2 * cache_slots_);
    return w;
  }

  // phi (N), d phi / d x (N x 2n), (d phi / d qd) dqd (N) and, when desired_jacobian is not null,
  // d phi / d qd (N x n), at x (2n), qd (n), dqd (n).
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& qd,
                const Eigen::Ref<const Eigen::VectorXd>& dqd, Eigen::Ref<Eigen::VectorXd> phi,
                Eigen::Ref<Eigen::MatrixXd> jacobian, Eigen::Ref<Eigen::VectorXd> desired_rate,
                Eigen::MatrixXd* desired_jacobian, Workspace& workspace) const {
    check_sizes(x, qd, dqd, phi, jacobian, desired_rate, desired_jacobian, workspace);
    Io io;
    io.x = x.data();
    io.qd = qd.data();
    io.dqd = dqd.data();
    io.phi = phi.data();
    io.jacobian = jacobian.data();
    io.jacobian_stride = jacobian.outerStride();
    io.desired_rate = desired_rate.data();
    io.desired_jacobian = desired_jacobian ? desired_jacobian->data() : nullptr;
    io.desired_stride = desired_jacobian ? desired_jacobian->outerStride() : 0;
    io.values = workspace.values.data();
    io.gradients = workspace.gradients.data();
    io.stride = workspace.gradients.rows();
    io.cache = workspace.cache.data();
    jacobian.setZero();
    if (desired_jacobian) desired_jacobian->setZero();
    for (std::size_t f = 0; f < functions_.size(); ++f) {
      if (functions_[f].monomial) {
        run_monomial(f, io);
        continue;
      }
      // the gradient loops unrolled for the common local counts (trig products)
      switch (functions_[f].local_count) {
        case 1:
          run<1>(f, io);
          break;
        case 2:
          run<2>(f, io);
          break;
        case 3:
          run<3>(f, io);
          break;
        case 4:
          run<4>(f, io);
          break;
        default:
          run<0>(f, io);
          break;
      }
    }
  }

  // The seam of basis.hpp: desired.q and desired.dq are qd and dqd (n each); these use the basis'
  // own workspace (one thread at a time), the form above takes one explicitly.
  template <class Desired>
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& x, const Desired& desired,
                Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> jacobian,
                Eigen::Ref<Eigen::VectorXd> desired_rate) {
    evaluate(x, desired.q, desired.dq, phi, jacobian, desired_rate, nullptr, workspace_);
  }
  template <class Desired, class Terms>
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& x, const Desired& desired, const Terms&,
                Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> jacobian,
                Eigen::Ref<Eigen::VectorXd> desired_rate) {
    evaluate(x, desired.q, desired.dq, phi, jacobian, desired_rate, nullptr, workspace_);
  }

 private:
  struct Instruction {
    ExpressionOp op;
    int index;        // variable: local index; power: the integer exponent
    double argument;  // constant: the value; power: the exponent
    bool integer;     // power: the exponent is an integer of magnitude <= 64
    int cache = -1;   // a function whose argument's program occurred before: its slot in the cache
    bool cache_write = false;  // the first occurrence (computes and writes; the others read)
  };
  struct Function {
    int begin, end;  // instructions in code_, the store excluded
    int locals_begin, local_count;
    // A monomial c prod_i z_i^p_i of distinct variables (p_i integers >= 1): evaluated without
    // the stack, with the same products in the same order (so the same numbers).
    bool monomial = false;
    int factors_begin = 0;  // in monomial_exponents_, one per local variable, in program order
    double coefficient = 1.0;
    bool has_coefficient = false;
  };
  static constexpr int kMaxMonomialFactors = 8;
  // Raw pointers of one evaluation (outputs column-major with their outer strides).
  struct Io {
    const double *x, *qd, *dqd;
    double *phi, *jacobian, *desired_rate, *desired_jacobian;
    Eigen::Index jacobian_stride, desired_stride;
    double *values, *gradients;
    Eigen::Index stride;
    double* cache;
  };

  // Runs function f (its instructions, then the store) with K local variables (0: any).
  template <int K>
  void run(std::size_t f, const Io& io) const {
    const int n_x = state_dim();
    const double *x = io.x, *qd = io.qd;
    double *values = io.values, *gradients = io.gradients;
    const Eigen::Index stride = io.stride;
    const Function& function = functions_[f];
    const int k = K > 0 ? K : function.local_count;
    const int* locals = local_variables_.data() + function.locals_begin;
    int top = 0;  // number of values on the stack
    for (int i = function.begin; i < function.end; ++i) {
      const Instruction& in = code_[i];
      double* g = gradients + stride * top;  // slot `top` (a push writes here)
      switch (in.op) {
        case ExpressionOp::constant:
          values[top] = in.argument;
          for (int j = 0; j < k; ++j) g[j] = 0.0;
          ++top;
          break;
        case ExpressionOp::variable: {
          const int global = locals[in.index];
          values[top] = global < n_x ? x[global] : qd[global - n_x];
          for (int j = 0; j < k; ++j) g[j] = 0.0;
          g[in.index] = 1.0;
          ++top;
          break;
        }
        case ExpressionOp::add: {
          --top;
          double* a = g - 2 * stride;
          const double* b = g - stride;
          values[top - 1] += values[top];
          for (int j = 0; j < k; ++j) a[j] += b[j];
          break;
        }
        case ExpressionOp::subtract: {
          --top;
          double* a = g - 2 * stride;
          const double* b = g - stride;
          values[top - 1] -= values[top];
          for (int j = 0; j < k; ++j) a[j] -= b[j];
          break;
        }
        case ExpressionOp::multiply: {
          --top;
          double* a = g - 2 * stride;
          const double* b = g - stride;
          const double va = values[top - 1], vb = values[top];
          for (int j = 0; j < k; ++j) a[j] = a[j] * vb + va * b[j];
          values[top - 1] = va * vb;
          break;
        }
        case ExpressionOp::negate:
          values[top - 1] = -values[top - 1];
          scale(g - stride, k, -1.0);
          break;
        default: {  // a function of the top value: value and derivative, then the chain rule
          double& v = values[top - 1];
          double derivative;
          if (in.cache >= 0 && !in.cache_write) {  // the same argument as before: f and f' known
            v = io.cache[2 * in.cache];
            derivative = io.cache[2 * in.cache + 1];
          } else {
            derivative = unary(in, v);
            if (in.cache >= 0) {
              io.cache[2 * in.cache] = v;
              io.cache[2 * in.cache + 1] = derivative;
            }
          }
          scale(g - stride, k, derivative);
          break;
        }
      }
    }
    // the store: one value left in slot 0
    io.phi[f] = values[0];
    double rate = 0.0;
    for (int j = 0; j < k; ++j) {
      const int global = locals[j];
      if (global < n_x) {
        io.jacobian[f + global * io.jacobian_stride] = gradients[j];
      } else {
        rate += gradients[j] * io.dqd[global - n_x];
        if (io.desired_jacobian)
          io.desired_jacobian[f + (global - n_x) * io.desired_stride] = gradients[j];
      }
    }
    io.desired_rate[f] = rate;
  }

  // Marks `function` a monomial when its code reads
  //   factor (factor multiply)* [constant c multiply | negate],  factor = variable [power p],
  // with distinct variables and integer exponents p >= 1.
  void detect_monomial(Function& function) {
    std::vector<int> order, exponents;
    int i = function.begin;
    const int end = function.end;
    auto factor = [&]() {
      if (i >= end || code_[i].op != ExpressionOp::variable) return false;
      const int local = code_[i++].index;
      int exponent = 1;
      if (i < end && code_[i].op == ExpressionOp::power) {
        if (!code_[i].integer || code_[i].index < 1) return false;
        exponent = code_[i++].index;
      }
      if (std::find(order.begin(), order.end(), local) != order.end()) return false;
      order.push_back(local);
      exponents.push_back(exponent);
      return true;
    };
    if (!factor()) return;
    while (i < end && code_[i].op == ExpressionOp::variable) {
      if (!factor() || i >= end || code_[i].op != ExpressionOp::multiply) return;
      ++i;
    }
    double coefficient = 1.0;
    bool has_coefficient = false;
    if (i + 1 < end && code_[i].op == ExpressionOp::constant &&
        code_[i + 1].op == ExpressionOp::multiply) {
      coefficient = code_[i].argument;
      has_coefficient = true;
      i += 2;
    } else if (i < end && code_[i].op == ExpressionOp::negate) {
      coefficient = -1.0;
      has_coefficient = true;
      ++i;
    }
    if (i != end || static_cast<int>(order.size()) > kMaxMonomialFactors) return;
    function.monomial = true;
    function.factors_begin = static_cast<int>(monomial_order_.size());
    function.coefficient = coefficient;
    function.has_coefficient = has_coefficient;
    monomial_order_.insert(monomial_order_.end(), order.begin(), order.end());
    monomial_exponents_.insert(monomial_exponents_.end(), exponents.begin(), exponents.end());
  }

  // A monomial function f: the products of the stack program, in its order (power(), then the
  // product rule with one nonzero gradient entry per factor), without the stack.
  void run_monomial(std::size_t f, const Io& io) const {
    const double *x = io.x, *qd = io.qd;
    const Function& function = functions_[f];
    const int m = function.local_count;
    const int* locals = local_variables_.data() + function.locals_begin;
    const int* order = monomial_order_.data() + function.factors_begin;
    const int* exponents = monomial_exponents_.data() + function.factors_begin;
    const int n_x = state_dim();
    double value[kMaxMonomialFactors], derivative[kMaxMonomialFactors], prefix[kMaxMonomialFactors];
    for (int i = 0; i < m; ++i) {
      const int global = locals[order[i]];
      const double b = global < n_x ? x[global] : qd[global - n_x];
      const int e = exponents[i];
      if (e == 1) {
        value[i] = b;
        derivative[i] = 1.0;
      } else {
        double p = b;  // b^(e - 1)
        for (int t = 2; t < e; ++t) p *= b;
        value[i] = p * b;
        derivative[i] = static_cast<double>(e) * p;
      }
      prefix[i] = i == 0 ? value[0] : prefix[i - 1] * value[i];
    }
    const double c = function.coefficient;
    const std::size_t row = f;
    io.phi[row] = function.has_coefficient ? prefix[m - 1] * c : prefix[m - 1];
    double rate = 0.0;
    for (int j = 0; j < m; ++j) {
      double g = j == 0 ? derivative[0] : prefix[j - 1] * derivative[j];
      for (int i = j + 1; i < m; ++i) g *= value[i];
      if (function.has_coefficient) g *= c;
      const int global = locals[order[j]];
      if (global < n_x) {
        io.jacobian[row + global * io.jacobian_stride] = g;
      } else {
        rate += g * io.dqd[global - n_x];
        if (io.desired_jacobian) io.desired_jacobian[row + (global - n_x) * io.desired_stride] = g;
      }
    }
    io.desired_rate[row] = rate;
  }

  static void scale(double* g, int k, double factor) {
    for (int j = 0; j < k; ++j) g[j] *= factor;
  }

  // Replaces v by f(v) and returns f'(v).
  static double unary(const Instruction& in, double& v) {
    const double u = v;
    switch (in.op) {
      case ExpressionOp::power:
        return power(in, v);
      case ExpressionOp::sin:
        v = std::sin(u);
        return std::cos(u);
      case ExpressionOp::cos:
        v = std::cos(u);
        return -std::sin(u);
      case ExpressionOp::tan: {
        v = std::tan(u);
        return 1.0 + v * v;
      }
      case ExpressionOp::exp:
        v = std::exp(u);
        return v;
      case ExpressionOp::log:
        v = std::log(u);
        return 1.0 / u;
      case ExpressionOp::sqrt:
        v = std::sqrt(u);
        return 0.5 / v;
      case ExpressionOp::tanh:
      default:
        v = std::tanh(u);
        return 1.0 - v * v;
    }
  }

  static double power(const Instruction& in, double& v) {
    const double b = v;
    if (!in.integer) {
      if (in.argument == 0.5) {
        v = std::sqrt(b);
        return 0.5 / v;
      }
      v = std::pow(b, in.argument);
      return in.argument * std::pow(b, in.argument - 1.0);
    }
    const int n = in.index;
    if (n == 0) {
      v = 1.0;
      return 0.0;
    }
    const int m = n > 0 ? n : -n;
    double p = 1.0;  // b^(m - 1)
    for (int i = 1; i < m; ++i) p = i == 1 ? b : p * b;
    const double bm = m == 1 ? b : p * b;  // b^m (b^2 = b b, b^3 = (b b) b, ...)
    if (n > 0) {
      v = bm;
      return static_cast<double>(m) * p;  // m b^(m - 1)
    }
    v = 1.0 / bm;
    return -static_cast<double>(m) * p / (bm * bm);  // -m b^(m-1) / b^(2m)
  }

  [[noreturn]] static void refuse(std::size_t i, const std::string& what) {
    std::ostringstream message;
    message << "expression basis program, instruction " << i << ": " << what;
    throw std::invalid_argument(message.str());
  }

  void compile(const std::vector<ExpressionInstruction>& program) {
    int top = 0;
    std::vector<int> globals;  // the variables the current function reads, sorted
    std::vector<Instruction> pending;
    std::vector<int> starts;  // per stack value: where in `pending` its program starts
    std::map<std::vector<double>, int> functions_seen;  // a function with its argument's program
    for (std::size_t i = 0; i < program.size(); ++i) {
      const ExpressionInstruction& in = program[i];
      const int code = static_cast<int>(in.op);
      if (code < 0 || code > static_cast<int>(ExpressionOp::store))
        refuse(i, "unknown opcode " + std::to_string(code));
      if (!std::isfinite(in.argument)) refuse(i, "argument must be finite");
      Instruction out{in.op, 0, in.argument, false};
      int pops = 0, pushes = 0;
      switch (in.op) {
        case ExpressionOp::constant:
          pushes = 1;
          break;
        case ExpressionOp::variable: {
          if (in.argument != std::floor(in.argument) || in.argument < 0 ||
              in.argument >= variables()) {
            std::ostringstream what;
            what << "unknown variable index " << in.argument << " (z = [x; qd] has " << variables()
                 << " variables for " << joints_ << " joints)";
            refuse(i, what.str());
          }
          const int global = static_cast<int>(in.argument);
          out.index = global;  // made local at the store
          auto at = std::lower_bound(globals.begin(), globals.end(), global);
          if (at == globals.end() || *at != global) globals.insert(at, global);
          pushes = 1;
          break;
        }
        case ExpressionOp::add:
        case ExpressionOp::subtract:
        case ExpressionOp::multiply:
          pops = 2;
          pushes = 1;
          break;
        case ExpressionOp::power:
          if (in.argument == std::floor(in.argument) && std::abs(in.argument) <= 64.0) {
            out.integer = true;
            out.index = static_cast<int>(in.argument);
          }
          pops = pushes = 1;
          break;
        case ExpressionOp::store:
          if (top != 1) {
            std::ostringstream what;
            what << "store of function " << functions_.size() << " needs exactly one value on the "
                 << "stack, found " << top;
            refuse(i, what.str());
          }
          pops = 1;
          break;
        default:  // negate and the functions
          pops = pushes = 1;
          break;
      }
      if (top < pops)
        refuse(i, "stack underflow (the operation needs " + std::to_string(pops) +
                      " values, the stack has " + std::to_string(top) + ")");
      top += pushes - pops;
      depth_ = std::max(depth_, top);
      if (pops == 0) {
        starts.push_back(static_cast<int>(pending.size()));
      } else if (pops == 2) {
        starts.pop_back();  // a op b starts where a does
      } else if (in.op == ExpressionOp::store) {
        starts.clear();
      } else if (in.op >= ExpressionOp::sin && in.op <= ExpressionOp::tanh) {
        // the same function of the same program (in global variables) gives the same numbers:
        // computed once per evaluation
        std::vector<double> key;
        for (std::size_t j = static_cast<std::size_t>(starts.back()); j < pending.size(); ++j)
          key.insert(key.end(), {static_cast<double>(pending[j].op), pending[j].argument,
                                 static_cast<double>(pending[j].index)});
        key.push_back(static_cast<double>(in.op));
        const auto found = functions_seen.find(key);
        if (found == functions_seen.end()) {
          out.cache = cache_slots_;
          out.cache_write = true;
          functions_seen.emplace(std::move(key), cache_slots_++);
        } else {
          out.cache = found->second;
        }
      }
      if (in.op != ExpressionOp::store) {
        pending.push_back(out);
        continue;
      }
      // close the function: variable indices become positions in its sorted variable list
      Function function;
      function.begin = static_cast<int>(code_.size());
      function.locals_begin = static_cast<int>(local_variables_.size());
      function.local_count = static_cast<int>(globals.size());
      for (Instruction& p : pending) {
        if (p.op == ExpressionOp::variable)
          p.index = static_cast<int>(std::lower_bound(globals.begin(), globals.end(), p.index) -
                                     globals.begin());
        code_.push_back(p);
      }
      function.end = static_cast<int>(code_.size());
      detect_monomial(function);
      local_variables_.insert(local_variables_.end(), globals.begin(), globals.end());
      max_locals_ = std::max(max_locals_, function.local_count);
      functions_.push_back(function);
      pending.clear();
      globals.clear();
    }
    if (top != 0 || !pending.empty()) {
      std::ostringstream what;
      what << "the program ends with " << pending.size() << " instructions (" << top
           << " values) after its last store";
      refuse(program.size() - 1, what.str());
    }
    if (functions_.empty())
      throw std::invalid_argument("expression basis program: no function (no store instruction)");
  }

  template <class X, class Q, class D, class P, class J, class R>
  void check_sizes(const X& x, const Q& qd, const D& dqd, const P& phi, const J& jacobian,
                   const R& desired_rate, const Eigen::MatrixXd* desired_jacobian,
                   const Workspace& workspace) const {
    const Eigen::Index n = joints_, n_x = state_dim(), N = size();
    check(x.size() == n_x, "x", n_x, 1, x.rows(), x.cols());
    check(qd.size() == n, "qd", n, 1, qd.rows(), qd.cols());
    check(dqd.size() == n, "dqd", n, 1, dqd.rows(), dqd.cols());
    check(phi.size() == N, "phi", N, 1, phi.rows(), phi.cols());
    check(jacobian.rows() == N && jacobian.cols() == n_x, "jacobian", N, n_x, jacobian.rows(),
          jacobian.cols());
    check(desired_rate.size() == N, "desired_rate", N, 1, desired_rate.rows(), desired_rate.cols());
    if (desired_jacobian)
      check(desired_jacobian->rows() == N && desired_jacobian->cols() == n, "desired_jacobian", N,
            n, desired_jacobian->rows(), desired_jacobian->cols());
    check(workspace.values.size() == depth_ && workspace.cache.size() == 2 * cache_slots_ &&
              workspace.gradients.rows() == std::max(max_locals_, 1) &&
              workspace.gradients.cols() == depth_,
          "workspace", std::max(max_locals_, 1), depth_, workspace.gradients.rows(),
          workspace.gradients.cols());
  }

  // Fills pairs_ when every function is a monomial of degree 2 in x alone (pairs()).
  void find_pairs() {
    Pairs found;
    const int n = joints_, n_x = state_dim();
    for (const Function& function : functions_) {
      if (!function.monomial) return;
      const int* locals = local_variables_.data() + function.locals_begin;
      const int* order = monomial_order_.data() + function.factors_begin;
      const int* exponents = monomial_exponents_.data() + function.factors_begin;
      int a = -1, b = -1;
      if (function.local_count == 2 && exponents[0] == 1 && exponents[1] == 1) {
        a = locals[order[0]];
        b = locals[order[1]];
      } else if (function.local_count == 1 && exponents[0] == 2) {
        a = b = locals[order[0]];
      }
      if (a < 0 || a >= n_x || b >= n_x) return;  // not a pair of x's entries
      found.term_x.push_back(b);
      found.term_z.push_back(a >= n ? a - n : -1);
      found.term_x.push_back(a);
      found.term_z.push_back(b >= n ? b - n : -1);
      found.coefficient.push_back(function.coefficient);
    }
    pairs_ = std::move(found);
  }

  static void check(bool ok, const char* name, Eigen::Index rows, Eigen::Index cols,
                    Eigen::Index got_rows, Eigen::Index got_cols) {
    if (ok) return;
    std::ostringstream message;
    message << name << ": expected shape (" << rows << ", " << cols << "), got (" << got_rows
            << ", " << got_cols << ")";
    throw std::invalid_argument(message.str());
  }

  int joints_;
  int depth_ = 0;
  int max_locals_ = 0;
  int cache_slots_ = 0;
  std::vector<Instruction> code_;
  std::vector<int> monomial_order_;      // local variable of each factor, in program order
  std::vector<int> monomial_exponents_;  // its exponent
  std::vector<int> local_variables_;
  std::vector<Function> functions_;
  Workspace workspace_;
  Pairs pairs_;
};

// The expression basis behind the loop's basis seam (basis.hpp) with dynamic sizes, for
// ClosedLoop<Arm, ExpressionLoopBasis> with a dynamic-size arm (DynamicArm<TwoLinkArm>). The
// compiled basis is shared (immutable); the loop owns a Workspace (workspace(), sized once) and
// passes it, so a loop (one thread) evaluates it without heap allocation. The arm's terms are not
// used. It has no paper e2 block (positive_block.hpp leaves its weights alone).
class ExpressionLoopBasis {
 public:
  static constexpr int kSize = Dynamic;
  static constexpr int kStateDim = Dynamic;
  using Vector = BasisVector<Dynamic>;
  using Jacobian = BasisMatrix<Dynamic, Dynamic>;

  // `name` names the settings field in the errors (an empty or malformed program).
  ExpressionLoopBasis(int joints, const ExpressionProgram& program,
                      const std::string& name = "basis_program")
      : basis_(std::make_shared<const ExpressionBasis>(joints, checked(program, name))) {}

  using Workspace = ExpressionBasis::Workspace;
  Workspace workspace() const { return basis_->workspace(); }

  int size() const { return basis_->size(); }
  int joints() const { return basis_->joints(); }
  const ExpressionBasis& expression() const { return *basis_; }
  // The basis-of-pairs seam (ClosedLoop's stacked points): ExpressionBasis::pairs().
  const ExpressionBasis::Pairs& pairs() const { return basis_->pairs(); }

  template <class Desired, class Terms>
  void evaluate(const ErrorVector<Dynamic>& x, const Desired& desired, const Terms&, Vector& phi,
                Jacobian& jacobian, Vector& desired_rate, Workspace& workspace) const {
    const Eigen::Index k = size(), n_x = basis_->state_dim();
    phi.resize(k);  // bounded storage: no allocation
    jacobian.resize(k, n_x);
    desired_rate.resize(k);
    basis_->evaluate(x, desired.q, desired.dq, phi, jacobian, desired_rate, nullptr, workspace);
  }

 private:
  static std::vector<ExpressionInstruction> checked(const ExpressionProgram& program,
                                                    const std::string& name) {
    if (program.opcodes.empty())
      throw std::invalid_argument(name +
                                  ": empty (controller.basis = expression needs the "
                                  "compiled program of its terms)");
    return expression_instructions(program, name);
  }

  std::shared_ptr<const ExpressionBasis> basis_;
};

}  // namespace adparm
