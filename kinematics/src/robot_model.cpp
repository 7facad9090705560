// URDF -> RobotModel through urdfdom. urdfdom reports its reasons through
// console_bridge (to stderr) and returns nullptr; we capture those messages and
// put them in our own exception, so the user sees one message naming the file.
// The tree is walked from the root through child joints sorted by name, never
// through urdfdom's std::map order (docs/toolchain.md, gotcha 4).
#include "fgcal/kinematics/robot_model.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include "fgcal/kinematics/errors.hpp"

namespace fgcal::kinematics {

const char* toString(JointType type) {
  switch (type) {
    case JointType::Revolute: return "revolute";
    case JointType::Continuous: return "continuous";
    case JointType::Prismatic: return "prismatic";
    case JointType::Fixed: return "fixed";
    case JointType::Floating: return "floating";
    case JointType::Planar: return "planar";
  }
  return "unknown";
}

namespace {

std::string label(const std::string& source) { return "URDF '" + source + "'"; }

// console_bridge keeps a raw pointer to its handler (and to the previous one),
// so the handler lives for the whole program; it only records while armed.
class CapturingHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (!sink_) return;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) sink_->errors.push_back(text);
    else if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) sink_->warnings.push_back(text);
  }
  struct Sink {
    std::vector<std::string> errors, warnings;
  };
  Sink* sink_ = nullptr;
};

urdf::ModelInterfaceSharedPtr parseQuietly(const std::string& xml, CapturingHandler::Sink& sink) {
  static std::mutex mutex;
  static CapturingHandler handler;
  std::lock_guard<std::mutex> lock(mutex);
  console_bridge::OutputHandler* const previous = console_bridge::getOutputHandler();
  const console_bridge::LogLevel previous_level = console_bridge::getLogLevel();
  handler.sink_ = &sink;
  console_bridge::useOutputHandler(&handler);
  // Errors must reach us even when the application silenced console_bridge.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    sink.errors.push_back(e.what());
    model.reset();
  }
  console_bridge::useOutputHandler(previous);
  console_bridge::setLogLevel(previous_level);
  handler.sink_ = nullptr;
  return model;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

// At most `max` names, then "... (N in all)": enough to spot a typo.
std::string someNames(std::vector<std::string> names, std::size_t max = 16) {
  const std::size_t n = names.size();
  if (n > max) {
    names.resize(max);
    return join(names, ", ") + ", ... (" + std::to_string(n) + " in all)";
  }
  return join(names, ", ");
}

// The text parsed as urdfdom parses it (the same TinyXML, the same call), so
// that the tree check below sees exactly the elements urdfdom will link.
void parseWellFormed(const std::string& xml, const std::string& source, TiXmlDocument* doc) {
  if (xml.find_first_not_of(" \t\r\n") == std::string::npos)
    throw UrdfError(label(source) + " is empty; expected a <robot> description");
  doc->Parse(xml.c_str());
  if (doc->Error()) {
    std::ostringstream s;
    s << label(source) << " is not well-formed XML (line " << doc->ErrorRow() << ", column " << doc->ErrorCol()
      << ": " << doc->ErrorDesc() << ")";
    throw UrdfError(s.str());
  }
}

[[noreturn]] void throwInvalid(const std::string& source, const CapturingHandler::Sink& sink) {
  std::ostringstream s;
  s << label(source);
  s << " is not a valid URDF: ";
  const auto& reasons = sink.errors.empty() ? sink.warnings : sink.errors;
  s << (reasons.empty() ? std::string("urdfdom rejected it without a reason") : "urdfdom says: " + join(reasons, "; "));
  const std::string all = join(reasons, " ");
  if (all.find("root link") != std::string::npos) {
    s << ". The links must form one tree: links in separate trees have no path between them";
  } else if (all.find("'robot' element") != std::string::npos) {
    s << ". Expected a <robot name=...> root element";
  }
  throw UrdfError(s.str());
}

// Length of the valid UTF-8 sequence starting at b[i] (0 when it is not one).
// TinyXML, which urdfdom parses with, trusts UTF-8 lead bytes: a truncated or
// invalid sequence makes it read past the end of the text (heap overflow found
// by fuzz/fuzz_urdf.cpp), so such text never reaches it.
std::size_t utf8SequenceLength(const unsigned char* b, std::size_t n, std::size_t i) {
  const unsigned char c = b[i];
  std::size_t len = 0;
  unsigned min = 0;
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) len = 2, min = 0x80;
  else if (c >= 0xE0 && c <= 0xEF) len = 3, min = 0x800;
  else if (c >= 0xF0 && c <= 0xF4) len = 4, min = 0x10000;
  else return 0;
  if (i + len > n) return 0;
  unsigned cp = c & (0x7F >> len);
  for (std::size_t k = 1; k < len; ++k) {
    if ((b[i + k] & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b[i + k] & 0x3F);
  }
  if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return len;
}

// The text as valid UTF-8: a leading byte-order mark dropped, valid sequences
// kept as they are (non-ASCII link names still match rig.yaml), and every byte
// that is not part of one read as Latin-1 (e.g. an author's name in a comment).
std::string asUtf8(const std::string& s) {
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = (n >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF) ? 3 : 0;
  std::string out;
  out.reserve(n + n / 8);
  while (i < n) {
    const std::size_t len = utf8SequenceLength(b, n, i);
    if (len > 0) {
      out.append(s, i, len);
      i += len;
    } else {
      out += static_cast<char>(0xC0 | (b[i] >> 6));
      out += static_cast<char>(0x80 | (b[i] & 0x3F));
      ++i;
    }
  }
  return out;
}

// What keeps the joints from forming a tree, checked on the XML before
// urdfdom sees it: "" when nothing does. urdfdom links the links of every
// joint to each other (child_links, shared pointers) before it looks for the
// root, so a loop of joints (a -> b -> ... -> a) is a cycle of shared pointers
// it never frees. A link that is the child of two joints can close such a
// loop unseen by a walk up one parent per link (a -> b, b -> c, c -> b: the
// root a is found, urdfdom returns the model, and walking it down never ends;
// found by fuzz/fuzz_urdf_origin.cpp), so that is refused first; then each
// link has one parent and walking up from every link finds any loop.
std::string treeViolation(const TiXmlDocument& doc) {
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (!robot) return "";
  struct Parent {
    std::string link, joint;
  };
  std::unordered_map<std::string, Parent> parent_of;  // child link -> its parent link and joint
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* pl = p ? p->Attribute("link") : nullptr;
    const char* cl = c ? c->Attribute("link") : nullptr;
    if (!pl || !cl) continue;
    const char* name = j->Attribute("name");
    const auto [it, added] = parent_of.emplace(cl, Parent{pl, name ? name : "(no name)"});
    if (!added)
      return "link '" + std::string(cl) + "' is the child of two joints, '" + it->second.joint + "' and '" +
             (name ? name : "(no name)") + "'";
  }
  for (const auto& start : parent_of) {
    std::vector<std::string> path{start.first};
    std::string link = start.first;
    for (std::size_t step = 0; step <= parent_of.size(); ++step) {
      const auto it = parent_of.find(link);
      if (it == parent_of.end()) break;
      link = it->second.link;
      if (link == start.first) {
        std::string s = "its joints form a loop (parent -> child: ";
        for (auto r = path.rbegin(); r != path.rend(); ++r) s += *r + " -> ";
        return s + link + ")";
      }
      path.push_back(link);
    }
  }
  return "";
}

SE3 toSE3(const urdf::Pose& p) {
  const Eigen::Quaterniond q(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  return SE3(SO3(q), Vec3(p.position.x, p.position.y, p.position.z));
}

JointType toJointType(int t, const std::string& joint, const std::string& source) {
  switch (t) {
    case urdf::Joint::REVOLUTE: return JointType::Revolute;
    case urdf::Joint::CONTINUOUS: return JointType::Continuous;
    case urdf::Joint::PRISMATIC: return JointType::Prismatic;
    case urdf::Joint::FIXED: return JointType::Fixed;
    case urdf::Joint::FLOATING: return JointType::Floating;
    case urdf::Joint::PLANAR: return JointType::Planar;
    default: break;
  }
  throw UrdfError(label(source) + ": joint '" + joint +
                  "' has an unknown type; expected revolute, continuous, prismatic, fixed, floating or planar");
}

}  // namespace

// Converts urdfdom's model into ours (friend of RobotModel).
class RobotModelBuilder {
 public:
  static RobotModel build(const std::string& raw_xml, const std::string& source) {
    // TinyXML must only see valid UTF-8; text that is not (e.g. a Latin-1
    // comment with an author's name) is read as Latin-1 and converted.
    const std::string xml = asUtf8(raw_xml);
    TiXmlDocument doc;
    parseWellFormed(xml, source, &doc);
    const std::string not_a_tree = treeViolation(doc);
    if (!not_a_tree.empty())
      throw UrdfError(label(source) + " is not a valid URDF: " + not_a_tree + "; expected the links to form one tree");
    CapturingHandler::Sink sink;
    const urdf::ModelInterfaceSharedPtr m = parseQuietly(xml, sink);
    if (!m || !m->getRoot()) throwInvalid(source, sink);

    RobotModel out;
    out.name_ = m->getName();
    out.source_ = source;
    out.root_link_ = m->getRoot()->name;

    // Depth-first from the root; children by joint name for a stable order.
    std::vector<urdf::LinkConstSharedPtr> stack{m->getRoot()};
    while (!stack.empty()) {
      const urdf::LinkConstSharedPtr link = stack.back();
      stack.pop_back();
      LinkInfo li;
      li.name = link->name;
      if (link->parent_joint) {
        li.parent_joint = link->parent_joint->name;
        out.joints_.push_back(convertJoint(*link->parent_joint, source));
      }
      std::vector<urdf::JointSharedPtr> children = link->child_joints;
      std::sort(children.begin(), children.end(),
                [](const urdf::JointSharedPtr& a, const urdf::JointSharedPtr& b) { return a->name < b->name; });
      for (const auto& j : children) li.child_joints.push_back(j->name);
      if (link->inertial) {
        const urdf::Inertial& in = *link->inertial;
        li.has_inertial = true;
        li.mass = in.mass;
        li.T_link_com = toSE3(in.origin);
        li.inertia << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      }
      out.links_.push_back(std::move(li));
      // Never walk a cycle, whatever urdfdom returned (treeViolation refuses the known ones).
      if (out.links_.size() > m->links_.size())
        throw UrdfError(label(source) + ": link '" + out.links_.back().name + "' is reached twice from root link '" +
                        out.root_link_ + "'; expected the links to form one tree");
      // Push in reverse so that the first child (by name) is visited first.
      for (auto it = children.rbegin(); it != children.rend(); ++it) {
        const urdf::LinkConstSharedPtr child = m->getLink((*it)->child_link_name);
        if (!child) {
          throw UrdfError(label(source) + ": joint '" + (*it)->name + "' names child link '" +
                          (*it)->child_link_name + "', which does not exist");
        }
        stack.push_back(child);
      }
    }
    if (out.links_.size() != m->links_.size()) {
      throw UrdfError(label(source) + ": only " + std::to_string(out.links_.size()) + " of its " +
                      std::to_string(m->links_.size()) + " links are reachable from root link '" + out.root_link_ +
                      "'; expected one tree");
    }
    for (std::size_t i = 0; i < out.links_.size(); ++i) out.link_index_[out.links_[i].name] = i;
    for (std::size_t i = 0; i < out.joints_.size(); ++i) out.joint_index_[out.joints_[i].name] = i;
    return out;
  }

 private:
  static JointInfo convertJoint(const urdf::Joint& j, const std::string& source) {
    JointInfo ji;
    ji.name = j.name;
    ji.type = toJointType(j.type, j.name, source);
    ji.parent_link = j.parent_link_name;
    ji.child_link = j.child_link_name;
    ji.T_parent_joint = toSE3(j.parent_to_joint_origin_transform);
    if (!ji.T_parent_joint.matrix().allFinite())
      throw UrdfError(label(source) + ": joint '" + j.name + "' has a non-finite <origin>; expected finite xyz and rpy");
    const Vec3 axis(j.axis.x, j.axis.y, j.axis.z);
    if (isMovable(ji.type)) {
      // urdfdom keeps the axis as written: normalize it, and refuse a zero one
      // rather than inventing a direction.
      const double n = axis.norm();
      if (!(n > 1e-9) || !std::isfinite(n)) {
        std::ostringstream s;
        s << label(source) << ": joint '" << j.name << "' (" << toString(ji.type) << ") has axis xyz=\""
          << axis.transpose() << "\"; expected a non-zero, finite axis";
        throw UrdfError(s.str());
      }
      ji.axis = axis / n;
    } else {
      ji.axis = axis.norm() > 0.0 ? Vec3(axis.normalized()) : Vec3(Vec3::UnitX());
    }
    if (j.limits && ji.type != JointType::Continuous) {
      ji.limits.has_position_limits = true;
      ji.limits.lower = j.limits->lower;
      ji.limits.upper = j.limits->upper;
    }
    if (j.limits) {
      ji.limits.effort = j.limits->effort;
      ji.limits.velocity = j.limits->velocity;
    }
    if (j.mimic) ji.mimic_joint = j.mimic->joint_name;
    return ji;
  }
};

RobotModel RobotModel::fromString(const std::string& urdf_xml, const std::string& source) {
  return RobotModelBuilder::build(urdf_xml, source);
}

RobotModel RobotModel::fromFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw UrdfError(label(path) + " is a directory; expected a .urdf file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw UrdfError(label(path) + " cannot be opened: " + std::strerror(err) + "; expected a readable .urdf file");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw UrdfError(label(path) + " could not be read to the end");
  return fromString(text.str(), path);
}

std::vector<std::string> RobotModel::linkNames() const {
  std::vector<std::string> out;
  for (const auto& l : links_) out.push_back(l.name);
  return out;
}

std::vector<std::string> RobotModel::jointNames() const {
  std::vector<std::string> out;
  for (const auto& j : joints_) out.push_back(j.name);
  return out;
}

std::vector<std::string> RobotModel::movableJointNames() const {
  std::vector<std::string> out;
  for (const auto& j : joints_)
    if (isMovable(j.type)) out.push_back(j.name);
  return out;
}

std::vector<std::string> RobotModel::leafLinks() const {
  std::vector<std::string> out;
  for (const auto& l : links_)
    if (l.child_joints.empty()) out.push_back(l.name);
  return out;
}

double RobotModel::totalMass() const {
  double m = 0.0;
  for (const auto& l : links_) m += l.mass;
  return m;
}

void RobotModel::requireLink(const std::string& name, const char* role) const {
  if (!hasLink(name)) {
    throw UrdfError(label(source_) + ": " + role + " link '" + name + "' is not a link of robot '" + name_ +
                    "'; its links are: " + someNames(linkNames()));
  }
}

const LinkInfo& RobotModel::link(const std::string& name) const {
  requireLink(name, "requested");
  return links_[link_index_.at(name)];
}

const JointInfo& RobotModel::joint(const std::string& name) const {
  const auto it = joint_index_.find(name);
  if (it == joint_index_.end()) {
    throw UrdfError(label(source_) + ": joint '" + name + "' is not a joint of robot '" + name_ +
                    "'; its joints are: " + someNames(jointNames()));
  }
  return joints_[it->second];
}

KinematicChain RobotModel::chain(const std::string& base_link, const std::string& tip_link) const {
  requireLink(base_link, "base");
  requireLink(tip_link, "tip");
  // Ancestors of the base (base first, root last), with their depth in that list.
  std::unordered_map<std::string, std::size_t> base_up;
  std::vector<const LinkInfo*> base_path;
  for (const LinkInfo* l = &links_[link_index_.at(base_link)];;) {
    base_up[l->name] = base_path.size();
    base_path.push_back(l);
    if (l->parent_joint.empty()) break;
    l = &links_[link_index_.at(joints_[joint_index_.at(l->parent_joint)].parent_link)];
  }
  // Walk up from the tip until a base ancestor: the deepest common ancestor.
  std::vector<const JointInfo*> down;  // tip first
  const LinkInfo* l = &links_[link_index_.at(tip_link)];
  while (!base_up.count(l->name)) {
    if (l->parent_joint.empty()) {
      // Cannot happen for a model urdfdom accepted (one tree), kept as a guard.
      throw UrdfError(label(source_) + ": there is no path between links '" + base_link + "' and '" + tip_link +
                      "'; expected both in one tree");
    }
    const JointInfo* j = &joints_[joint_index_.at(l->parent_joint)];
    down.push_back(j);
    l = &links_[link_index_.at(j->parent_link)];
  }
  std::vector<PathStep> path;
  const std::size_t up_count = base_up.at(l->name);
  for (std::size_t i = 0; i < up_count; ++i) {
    path.push_back(PathStep{joints_[joint_index_.at(base_path[i]->parent_joint)], true});
  }
  for (auto it = down.rbegin(); it != down.rend(); ++it) path.push_back(PathStep{**it, false});
  return KinematicChain(base_link, tip_link, path, source_);
}

}  // namespace fgcal::kinematics
