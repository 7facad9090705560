// The calibrated robot description (see urdf_update.hpp): which joint each
// camera's pose goes into, the text edit of its <origin>, and the check of the
// written file through urdfdom and fgcal's own chain walker.
#include "fgcal/apps/urdf_update.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <stdexcept>

#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps {

namespace {

// ---- A minimal XML tag scanner over the original text ------------------------
// Only what the edit needs: the position of every element tag, with comments,
// CDATA sections, processing instructions and the DOCTYPE skipped, so that a
// "<joint" inside any of them is never mistaken for an element.

struct Tag {
  enum class Kind { Start, End, Empty } kind = Kind::Start;
  std::string name;
  std::size_t begin = 0, end = 0;  // [begin, end) covers "<...>"
};

struct Attribute {
  std::string name;
  std::size_t value_begin = 0, value_end = 0;  // the raw text between the quotes
};

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

[[noreturn]] void malformed(const std::string& text, std::size_t pos, const std::string& what) {
  const long line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n');
  throw std::invalid_argument("malformed XML at line " + std::to_string(line) + ": " + what);
}

std::size_t findOrFail(const std::string& text, const std::string& what, std::size_t from, std::size_t at) {
  const std::size_t p = text.find(what, from);
  if (p == std::string::npos) malformed(text, at, "no closing '" + what + "'");
  return p;
}

/// The index of the '>' that closes a tag or declaration whose text goes on
/// at `from`: a '>' inside a quoted value does not close it, nor, with
/// `brackets` (a DOCTYPE's internal subset), one inside [...]. text.size()
/// when there is none.
std::size_t closingAngle(const std::string& text, std::size_t from, bool brackets) {
  int depth = 0;
  char quote = 0;
  for (std::size_t j = from; j < text.size(); ++j) {
    const char c = text[j];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (brackets && c == '[') {
      ++depth;
    } else if (brackets && c == ']') {
      --depth;
    } else if (c == '>' && depth <= 0) {
      return j;
    }
  }
  return text.size();
}

std::vector<Tag> scanTags(const std::string& text) {
  std::vector<Tag> tags;
  std::size_t i = 0;
  while ((i = text.find('<', i)) != std::string::npos) {
    if (text.compare(i, 4, "<!--") == 0) {
      i = findOrFail(text, "-->", i + 4, i) + 3;
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      i = findOrFail(text, "]]>", i + 9, i) + 3;
    } else if (text.compare(i, 2, "<?") == 0) {
      i = findOrFail(text, "?>", i + 2, i) + 2;
    } else if (text.compare(i, 2, "<!") == 0) {  // DOCTYPE, with an optional [internal subset]
      const std::size_t j = closingAngle(text, i + 2, true);
      if (j >= text.size()) malformed(text, i, "unterminated declaration");
      i = j + 1;
    } else {
      Tag t;
      t.begin = i;
      std::size_t j = i + 1;
      if (j < text.size() && text[j] == '/') {
        t.kind = Tag::Kind::End;
        ++j;
      }
      const std::size_t name_begin = j;
      while (j < text.size() && !isSpace(text[j]) && text[j] != '/' && text[j] != '>') ++j;
      t.name = text.substr(name_begin, j - name_begin);
      if (t.name.empty()) malformed(text, i, "a '<' that starts no element");
      j = closingAngle(text, j, false);
      if (j >= text.size()) malformed(text, i, "unterminated tag <" + t.name);
      if (t.kind == Tag::Kind::Start && text[j - 1] == '/') t.kind = Tag::Kind::Empty;
      t.end = j + 1;
      tags.push_back(t);
      i = t.end;
    }
  }
  return tags;
}

std::vector<Attribute> attributesOf(const std::string& text, const Tag& tag) {
  std::vector<Attribute> out;
  std::size_t j = tag.begin + 1 + tag.name.size();
  const std::size_t stop = tag.end - (tag.kind == Tag::Kind::Empty ? 2 : 1);
  while (true) {
    while (j < stop && isSpace(text[j])) ++j;
    if (j >= stop) break;
    Attribute a;
    const std::size_t nb = j;
    while (j < stop && !isSpace(text[j]) && text[j] != '=') ++j;
    a.name = text.substr(nb, j - nb);
    while (j < stop && isSpace(text[j])) ++j;
    if (j >= stop || text[j] != '=') malformed(text, tag.begin, "attribute '" + a.name + "' without a value");
    ++j;
    while (j < stop && isSpace(text[j])) ++j;
    if (j >= stop || (text[j] != '"' && text[j] != '\'')) malformed(text, tag.begin, "unquoted attribute value");
    const char q = text[j];
    const std::size_t ve = text.find(q, j + 1);
    if (ve == std::string::npos || ve >= stop) malformed(text, tag.begin, "unterminated attribute value");
    a.value_begin = j + 1;
    a.value_end = ve;
    out.push_back(a);
    j = ve + 1;
  }
  return out;
}

// Attribute text with XML's predefined and numeric character references resolved.
std::string decodeEntities(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '&') {
      out += s[i];
      continue;
    }
    const std::size_t semi = s.find(';', i);
    if (semi == std::string::npos) {
      out += s[i];
      continue;
    }
    const std::string ent = s.substr(i + 1, semi - i - 1);
    if (ent == "amp") out += '&';
    else if (ent == "lt") out += '<';
    else if (ent == "gt") out += '>';
    else if (ent == "quot") out += '"';
    else if (ent == "apos") out += '\'';
    else if (ent.size() > 1 && ent[0] == '#') {
      unsigned long cp = 0;
      try {
        cp = ent[1] == 'x' ? std::stoul(ent.substr(2), nullptr, 16) : std::stoul(ent.substr(1));
      } catch (const std::exception&) {
        out += s.substr(i, semi - i + 1);
        i = semi;
        continue;
      }
      if (cp < 0x80) {
        out += static_cast<char>(cp);
      } else if (cp < 0x800) {
        out += static_cast<char>(0xC0 | (cp >> 6));
        out += static_cast<char>(0x80 | (cp & 0x3F));
      } else if (cp < 0x10000) {
        out += static_cast<char>(0xE0 | (cp >> 12));
        out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (cp & 0x3F));
      } else {
        out += static_cast<char>(0xF0 | (cp >> 18));
        out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (cp & 0x3F));
      }
    } else {
      out += s.substr(i, semi - i + 1);
    }
    i = semi;
  }
  return out;
}

std::string three(double a, double b, double c) {
  return detail::formatDoubleCsv(a) + " " + detail::formatDoubleCsv(b) + " " + detail::formatDoubleCsv(c);
}

double rotationAngle(const SO3& a, const SO3& b) { return a.between(b).log().norm(); }

// ---- Tree queries on the robot model -----------------------------------------

// Joints from `link` up to the root, nearest first.
std::vector<std::string> jointsAbove(const kinematics::RobotModel& model, const std::string& link) {
  std::vector<std::string> out;
  std::string l = link;
  while (!model.link(l).parent_joint.empty()) {
    const auto& j = model.joint(model.link(l).parent_joint);
    out.push_back(j.name);
    l = j.parent_link;
  }
  return out;
}

// The joints the chain base -> frame walks downward (ancestors of the frame
// that are not ancestors of the base), nearest the frame first, and those it
// walks upward (ancestors of the base that are not ancestors of the frame).
struct ChainJoints {
  std::vector<std::string> down, up;
};

ChainJoints chainJoints(const kinematics::RobotModel& model, const std::string& base, const std::string& frame) {
  const std::vector<std::string> above_frame = jointsAbove(model, frame);
  const std::vector<std::string> above_base = jointsAbove(model, base);
  const std::set<std::string> fset(above_frame.begin(), above_frame.end()), bset(above_base.begin(), above_base.end());
  ChainJoints c;
  for (const auto& j : above_frame)
    if (!bset.count(j)) c.down.push_back(j);
  for (const auto& j : above_base)
    if (!fset.count(j)) c.up.push_back(j);
  return c;
}

SE3 fixedTransform(const kinematics::RobotModel& model, const std::string& from, const std::string& to) {
  if (from == to) return SE3();
  return model.chain(from, to).forward(VecX());
}

}  // namespace

int editDistance(const std::string& a, const std::string& b) {
  std::vector<int> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = static_cast<int>(i);
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const int sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::vector<std::string> closestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t count) {
  // Case does not count ("lf_foot" means LF_FOOT); a name inside the other
  // ("base" for base_link) comes first; then the edit distance relative to the
  // longer name, so that a long name one piece away ranks before a short
  // unrelated one ("imu" is 16 edits from "cam0_optical_frame", but most of
  // it).
  auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
  };
  const std::string key = lower(name);
  struct Scored {
    bool contained;
    double distance;
    const std::string* name;
  };
  std::vector<Scored> scored;
  for (const auto& c : candidates) {
    const std::string lc = lower(c);
    const bool contained = !key.empty() && !lc.empty() &&
                           (key.find(lc) != std::string::npos || lc.find(key) != std::string::npos);
    const double longer = static_cast<double>(std::max<std::size_t>({key.size(), lc.size(), 1}));
    scored.push_back({contained, editDistance(key, lc) / longer, &c});
  }
  std::stable_sort(scored.begin(), scored.end(), [](const Scored& x, const Scored& y) {
    if (x.contained != y.contained) return x.contained;
    return x.distance < y.distance;
  });
  std::vector<std::string> out;
  for (std::size_t i = 0; i < scored.size() && i < count; ++i) out.push_back(*scored[i].name);
  return out;
}

namespace {

/// The top-level <joint name="joint"> (a child of the root element), a start tag.
std::size_t findJointTag(const std::string& text, const std::vector<Tag>& tags, const std::string& joint) {
  int depth = 0;
  std::size_t joint_tag = tags.size();
  for (std::size_t k = 0; k < tags.size(); ++k) {
    const Tag& t = tags[k];
    if (t.kind == Tag::Kind::End) {
      --depth;
      continue;
    }
    if (depth == 1 && t.name == "joint") {
      for (const Attribute& a : attributesOf(text, t))
        if (a.name == "name" && decodeEntities(text.substr(a.value_begin, a.value_end - a.value_begin)) == joint) {
          if (joint_tag != tags.size())
            throw std::invalid_argument("joint '" + joint + "' is defined more than once");
          joint_tag = k;
        }
    }
    if (t.kind == Tag::Kind::Start) ++depth;
  }
  if (joint_tag == tags.size()) throw std::invalid_argument("no <joint name=\"" + joint + "\"> element");
  if (tags[joint_tag].kind != Tag::Kind::Start)
    throw std::invalid_argument("joint '" + joint + "' is an empty element");
  return joint_tag;
}

/// A joint element's first direct child <origin> and first child element of
/// any kind (tags.size() when none).
struct JointChildren {
  std::size_t origin, first_child;
};
JointChildren jointChildren(const std::vector<Tag>& tags, std::size_t joint_tag) {
  JointChildren c{tags.size(), tags.size()};
  int d = 0;
  for (std::size_t k = joint_tag + 1; k < tags.size(); ++k) {
    const Tag& t = tags[k];
    if (t.kind == Tag::Kind::End) {
      if (d == 0) break;  // </joint>
      --d;
      continue;
    }
    if (d == 0) {
      if (c.first_child == tags.size()) c.first_child = k;
      if (t.name == "origin" && c.origin == tags.size()) c.origin = k;
    }
    if (t.kind == Tag::Kind::Start) ++d;
  }
  return c;
}

/// A new <origin> element: before the joint's first child, on a line of its
/// own with the same indentation when the first child has one; right after
/// the joint's start tag when it has no child.
std::string insertOrigin(const std::string& text, const std::vector<Tag>& tags, const Tag& jt,
                         std::size_t first_child, const std::string& element) {
  std::string out = text;
  if (first_child == tags.size()) {
    out.insert(jt.end, element);
    return out;
  }
  const std::size_t at = tags[first_child].begin;
  const std::size_t nl = text.rfind('\n', at);
  const std::size_t line_start = nl == std::string::npos ? 0 : nl + 1;
  const std::string lead = text.substr(line_start, at - line_start);
  const bool own_line = nl != std::string::npos && nl >= jt.end &&
                        std::all_of(lead.begin(), lead.end(), [](char c) { return c == ' ' || c == '\t'; });
  out.insert(at, own_line ? element + "\n" + lead : element);
  return out;
}

/// The xyz and rpy values of an existing <origin> replaced in place (added
/// when missing), back to front so positions stay valid.
std::string replaceOriginValues(const std::string& text, const Tag& ot, const std::string& xyz,
                                const std::string& rpy) {
  std::string out = text;
  const std::vector<Attribute> attrs = attributesOf(text, ot);
  std::vector<std::pair<std::size_t, std::pair<std::size_t, std::string>>> edits;  // pos -> (erase, insert)
  std::string missing;
  for (const auto& kv : {std::pair<std::string, std::string>{"xyz", xyz}, {"rpy", rpy}}) {
    const std::string& key = kv.first;  // (a structured binding cannot be captured in C++17)
    const auto it = std::find_if(attrs.begin(), attrs.end(), [&key](const Attribute& a) { return a.name == key; });
    if (it != attrs.end())
      edits.push_back({it->value_begin, {it->value_end - it->value_begin, kv.second}});
    else
      missing += " " + key + "=\"" + kv.second + "\"";
  }
  if (!missing.empty()) {
    const std::size_t after = attrs.empty() ? ot.begin + 1 + ot.name.size() : attrs.back().value_end + 1;
    edits.push_back({after, {0, missing}});
  }
  std::sort(edits.begin(), edits.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [pos, e] : edits) out.replace(pos, e.first, e.second);
  return out;
}

}  // namespace

std::string setJointOrigin(const std::string& text, const std::string& joint, const SE3& T) {
  const std::vector<Tag> tags = scanTags(text);
  const std::size_t joint_tag = findJointTag(text, tags, joint);
  const JointChildren children = jointChildren(tags, joint_tag);
  const Vec6 p = T.xyzRpy();
  const std::string xyz = three(p[0], p[1], p[2]), rpy = three(p[3], p[4], p[5]);
  if (children.origin == tags.size())
    return insertOrigin(text, tags, tags[joint_tag], children.first_child,
                        "<origin xyz=\"" + xyz + "\" rpy=\"" + rpy + "\"/>");
  return replaceOriginValues(text, tags[children.origin], xyz, rpy);
}

namespace {

/// The joints from the base to a camera's frame, checked: the frame is a
/// link below the base, reached through fixed joints only.
ChainJoints cameraChain(const kinematics::RobotModel& model, const UrdfCameraFrame& cam, const std::string& urdf_path,
                        const std::string& base_link, const std::string& rig_path) {
  const std::string frame_field = cam.field + ".frame";
  if (!model.hasLink(cam.frame))
    throw InputError(rig_path, frame_field,
                     "expected a link of " + urdf_path + " (the camera's optical frame), got '" + cam.frame +
                         "'; closest link names: " + detail::joinNames(closestNames(cam.frame, model.linkNames())));
  if (cam.frame == base_link)
    throw InputError(rig_path, frame_field,
                     "expected the camera's optical frame, got the base link '" + base_link +
                         "' itself: no joint lies between them");
  ChainJoints c = chainJoints(model, base_link, cam.frame);
  for (const auto* part : {&c.up, &c.down})
    for (const auto& jn : *part) {
      const auto& j = model.joint(jn);
      if (j.type != kinematics::JointType::Fixed)
        throw InputError(rig_path, frame_field,
                         "the chain " + base_link + " -> " + cam.frame + " in " + urdf_path + " has the " +
                             kinematics::toString(j.type) + " joint '" + jn +
                             "': the camera's pose depends on that joint's value (e.g. a pan-tilt head), so no "
                             "fixed joint origin can hold its calibration; expected only fixed joints between "
                             "the base and the camera");
    }
  if (c.down.empty())
    throw InputError(rig_path, frame_field,
                     "'" + cam.frame + "' is an ancestor of the base link '" + base_link + "' in " + urdf_path +
                         ": no joint on the chain from the base leads down to it");
  return c;
}

/// The joint whose origin holds a camera's calibration: urdf_joint, checked
/// to lie above the frame, or by default the frame's own joint (the camera
/// body's joint when the own joint is the usual pure rotation into the
/// optical convention).
void chooseJoint(const kinematics::RobotModel& model, const UrdfCameraFrame& cam, const ChainJoints& c,
                 const std::string& urdf_path, const std::string& base_link, const std::string& rig_path,
                 UrdfJointEdit& e) {
  const std::string joint_field = cam.field + ".urdf_joint";
  if (cam.urdf_joint.empty()) {
    e.default_joint = true;
    e.joint = c.down.front();
    const auto& own = model.joint(e.joint);
    if (own.T_parent_joint.translation().norm() == 0.0 && c.down.size() > 1) e.joint = c.down[1];
    return;
  }
  if (!model.hasJoint(cam.urdf_joint))
    throw InputError(rig_path, joint_field,
                     "expected a joint of " + urdf_path + ", got '" + cam.urdf_joint + "'; closest joint names: " +
                         detail::joinNames(closestNames(cam.urdf_joint, model.jointNames())));
  if (std::find(c.down.begin(), c.down.end(), cam.urdf_joint) == c.down.end())
    throw InputError(rig_path, joint_field,
                     "expected a joint above '" + cam.frame + "' on the chain from " + base_link + ", got '" +
                         cam.urdf_joint + "'; the joints there are (frame first): " + detail::joinNames(c.down));
  e.joint = cam.urdf_joint;
}

/// One joint per camera, and none moving another camera.
void checkJointsIndependent(const UrdfUpdatePlan& plan, const std::vector<ChainJoints>& chains,
                            const std::vector<UrdfCameraFrame>& cameras, const std::string& rig_path) {
  for (std::size_t a = 0; a < plan.edits.size(); ++a)
    for (std::size_t b = 0; b < plan.edits.size(); ++b) {
      if (a == b) continue;
      const auto& down_b = chains[b].down;
      if (std::find(down_b.begin(), down_b.end(), plan.edits[a].joint) == down_b.end()) continue;
      const UrdfCameraFrame& ca = cameras[a];
      throw InputError(rig_path, ca.field + (ca.urdf_joint.empty() ? ".frame" : ".urdf_joint"),
                       "the joint '" + plan.edits[a].joint + "'" +
                           (plan.edits[a].default_joint ? " (the default for frame '" + ca.frame + "')" : "") +
                           " also lies on the chain of camera " + cameras[b].camera + " (frame '" +
                           cameras[b].frame + "'): updating it for camera " + ca.camera + " would move camera " +
                           cameras[b].camera + " too; expected urdf_joint to name a joint of " + ca.camera +
                           "'s own branch, e.g. '" + chains[a].down.front() + "'");
    }
}

}  // namespace

UrdfUpdatePlan planUrdfUpdate(const std::string& urdf_text, const std::string& urdf_path, const std::string& base_link,
                              const std::vector<UrdfCameraFrame>& cameras, const std::string& rig_path) {
  const kinematics::RobotModel model = kinematics::RobotModel::fromString(urdf_text, urdf_path);
  if (!model.hasLink(base_link))
    throw InputError(rig_path, "robot.base_link",  // robot_outputs adds rig.yaml's line
                     "'" + base_link + "' is not a link of " + urdf_path + "; closest: " +
                         detail::joinNames(closestNames(base_link, model.linkNames())));
  UrdfUpdatePlan plan;
  plan.urdf_path = urdf_path;
  plan.urdf_text = urdf_text;
  plan.base_link = base_link;
  std::vector<ChainJoints> chains;
  for (const UrdfCameraFrame& cam : cameras) {
    const ChainJoints c = cameraChain(model, cam, urdf_path, base_link, rig_path);
    UrdfJointEdit e;
    e.camera = cam.camera;
    e.frame = cam.frame;
    chooseJoint(model, cam, c, urdf_path, base_link, rig_path, e);
    const auto& j = model.joint(e.joint);
    try {  // the text edit must find the element now, not after the calibration
      setJointOrigin(urdf_text, e.joint, j.T_parent_joint);
    } catch (const std::invalid_argument& ex) {
      throw InputError(urdf_path, "joint " + e.joint, std::string("cannot update its <origin>: ") + ex.what());
    }
    e.T_base_parent = fixedTransform(model, base_link, j.parent_link);
    e.T_child_frame = fixedTransform(model, j.child_link, cam.frame);
    e.T_parent_child_before = j.T_parent_joint;
    plan.edits.push_back(e);
    chains.push_back(c);
  }
  checkJointsIndependent(plan, chains, cameras, rig_path);
  return plan;
}

UrdfUpdateResult applyUrdfUpdate(const UrdfUpdatePlan& plan, const std::map<std::string, SE3>& T_base_cam) {
  UrdfUpdateResult res;
  res.text = plan.urdf_text;
  for (const UrdfJointEdit& e : plan.edits) {
    const auto it = T_base_cam.find(e.camera);
    if (it == T_base_cam.end()) throw std::runtime_error("no calibrated pose for camera " + e.camera);
    const SE3 origin = e.T_base_parent.inverse() * it->second * e.T_child_frame.inverse();
    try {
      res.text = setJointOrigin(res.text, e.joint, origin);
    } catch (const std::invalid_argument& ex) {
      throw InputError(plan.urdf_path, "joint " + e.joint, std::string("cannot update its <origin>: ") + ex.what());
    }
  }
  // The check: what a consumer of the file will compute.
  const kinematics::RobotModel before = kinematics::RobotModel::fromString(plan.urdf_text, plan.urdf_path);
  const kinematics::RobotModel after = kinematics::RobotModel::fromString(res.text, plan.urdf_path + " (updated)");
  std::set<std::string> edited;
  for (const UrdfJointEdit& e : plan.edits) {
    edited.insert(e.joint);
    const SE3 T = after.chain(plan.base_link, e.frame).forward(VecX());
    const SE3& want = T_base_cam.at(e.camera);
    res.max_translation_error_m = std::max(res.max_translation_error_m, (T.translation() - want.translation()).norm());
    res.max_rotation_error_rad = std::max(res.max_rotation_error_rad, rotationAngle(T.so3(), want.so3()));
    ++res.cameras_checked;
  }
  if (!(res.max_translation_error_m <= kUrdfCheckTolerance && res.max_rotation_error_rad <= kUrdfCheckTolerance))
    throw std::runtime_error("the updated URDF does not reproduce the calibration: its chains differ by " +
                             detail::formatDoubleCsv(res.max_translation_error_m) + " m and " +
                             detail::formatDoubleCsv(res.max_rotation_error_rad) + " rad (tolerance " +
                             detail::formatDoubleCsv(kUrdfCheckTolerance) + "); nothing was written");
  if (before.joints().size() != after.joints().size() || before.links().size() != after.links().size())
    throw std::runtime_error("the updated URDF has other links or joints than " + plan.urdf_path +
                             "; nothing was written");
  for (const auto& jb : before.joints()) {
    if (edited.count(jb.name)) continue;
    const auto& ja = after.joint(jb.name);
    const bool same = ja.type == jb.type && ja.parent_link == jb.parent_link && ja.child_link == jb.child_link &&
                      ja.T_parent_joint.matrix() == jb.T_parent_joint.matrix() && ja.axis == jb.axis;
    if (!same)
      throw std::runtime_error("the updated URDF changed joint '" + jb.name + "', which was not to be edited; "
                               "nothing was written");
  }
  return res;
}

}  // namespace fgcal::apps
