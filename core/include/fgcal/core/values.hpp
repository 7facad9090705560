// Values: the current estimate of every variable, by key. A variable is any
// type with a Manifold<T> specialization (SE3, SO3, R^n fixed or dynamic);
// the optimizer sees only the type-erased Variable interface, so new variable
// types need no change to it.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <unordered_map>
#include <vector>

#include "fgcal/core/key.hpp"
#include "fgcal/core/manifold.hpp"

namespace fgcal {

class Variable {
 public:
  virtual ~Variable() = default;
  virtual int dim() const = 0;
  /// x <- x ⊕ delta, delta holding dim() entries.
  virtual void retract(const double* delta) = 0;
  /// out <- (other ⊖ this), the delta with this ⊕ delta = other.
  virtual void localCoordinates(const Variable& other, double* out) const = 0;
  virtual std::unique_ptr<Variable> clone() const = 0;
  virtual const std::type_info& type() const = 0;
};

template <class T>
class TypedVariable final : public Variable {
 public:
  explicit TypedVariable(T value) : value_(std::move(value)) {}
  int dim() const override { return Manifold<T>::dim(value_); }
  void retract(const double* delta) override {
    using Delta = Eigen::Matrix<double, Manifold<T>::kDim, 1>;
    value_ = Manifold<T>::plus(value_, Eigen::Map<const Delta>(delta, dim()));
  }
  void localCoordinates(const Variable& other, double* out) const override {
    using Delta = Eigen::Matrix<double, Manifold<T>::kDim, 1>;
    Eigen::Map<Delta>(out, dim()) =
        Manifold<T>::minus(value_, static_cast<const TypedVariable<T>&>(other).value_);
  }
  std::unique_ptr<Variable> clone() const override { return std::make_unique<TypedVariable<T>>(value_); }
  const std::type_info& type() const override { return typeid(T); }
  const T& value() const { return value_; }
  T& value() { return value_; }

 private:
  T value_;
};

class Values {
 public:
  Values() = default;
  Values(const Values& other);
  Values& operator=(const Values& other);
  Values(Values&&) noexcept = default;
  Values& operator=(Values&&) noexcept = default;

  /// Throws std::invalid_argument when the key is already there.
  template <class T>
  void insert(Key k, const T& value) {
    using S = Stored<T>;
    insertVariable(k, std::make_unique<TypedVariable<S>>(S(value)));
  }
  /// Replaces the value of an existing key (same type) or inserts it.
  template <class T>
  void insertOrAssign(Key k, const T& value) {
    const std::size_t i = find(k);
    if (i == npos) return insert(k, value);
    using S = Stored<T>;
    typed<S>(i, k).value() = S(value);
  }
  /// Throws std::out_of_range naming the key when absent, std::invalid_argument on a type mismatch.
  template <class T>
  const T& at(Key k) const {
    return typed<T>(indexOf(k), k).value();
  }

  bool exists(Key k) const { return find(k) != npos; }
  std::size_t size() const { return variables_.size(); }
  /// Keys in insertion order. The reference is valid until the next insert
  /// into this Values (an insert into a copy that still shares the keys gives
  /// that copy its own).
  const std::vector<Key>& keys() const { return index_ ? index_->keys : emptyKeys(); }
  /// Dense position of a key (insertion order); throws std::out_of_range when absent.
  std::size_t indexOf(Key k) const;
  /// Dense position of a key, or npos when absent (one lookup, no exception).
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t find(Key k) const {
    if (!index_) return npos;
    const auto it = index_->position.find(k);
    return it == index_->position.end() ? npos : it->second;
  }
  const Variable& variable(Key k) const { return *variables_[indexOf(k)]; }
  Variable& variable(Key k) { return *variables_[indexOf(k)]; }
  const Variable& variableAt(std::size_t i) const { return *variables_[i]; }
  Variable& variableAt(std::size_t i) { return *variables_[i]; }

  void insertVariable(Key k, std::unique_ptr<Variable> v);

 private:
  // Eigen expressions (VecX::Ones(5), a + b) are stored as their plain vector type.
  template <class T, class = void>
  struct StoredType {
    using type = T;
  };
  template <class T>
  struct StoredType<T, std::enable_if_t<std::is_base_of<Eigen::EigenBase<T>, T>::value>> {
    using type = typename T::PlainObject;
  };
  template <class T>
  using Stored = typename StoredType<T>::type;

  template <class T>
  TypedVariable<T>& typed(std::size_t i, Key k) const {
    Variable& v = *variables_[i];
    if (v.type() != typeid(T))
      throw std::invalid_argument("variable " + keyToString(k) + " is held with another type than requested");
    return static_cast<TypedVariable<T>&>(v);
  }

  static const std::vector<Key>& emptyKeys();

  std::vector<std::unique_ptr<Variable>> variables_;
  // The keys and their positions, shared by copies until one of them inserts
  // (copy on write): an estimate copied for an optimizer run (optimize()
  // copies its initial values) has the same keys, and a million-entry hash
  // map is not copied node by node for it.
  struct Index {
    std::vector<Key> keys;
    std::unordered_map<Key, std::size_t> position;
  };
  std::shared_ptr<Index> index_;
};

}  // namespace fgcal
