// The nodelet's ~ parameters checked before dynamic_reconfigure reads them,
// and a DoorStateConfig turned into the pipeline's YAML (see the header).
#include "door_state_recognition/ros/nodelet_parameters.hpp"

#include <xmlrpcpp/XmlRpcException.h>

#include <cmath>
#include <map>
#include <sstream>

#include "door_state_recognition/pipeline/parameters.hpp"

namespace door_state_recognition {

namespace {

bool isNumber(const XmlRpc::XmlRpcValue& v) {
  return v.getType() == XmlRpc::XmlRpcValue::TypeDouble || v.getType() == XmlRpc::XmlRpcValue::TypeInt;
}

double asDouble(XmlRpc::XmlRpcValue& v) {
  return v.getType() == XmlRpc::XmlRpcValue::TypeInt ? static_cast<double>(static_cast<int>(v)) : static_cast<double>(v);
}

std::string typeName(const XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return "a bool";
    case XmlRpc::XmlRpcValue::TypeInt: return "an int";
    case XmlRpc::XmlRpcValue::TypeDouble: return "a double";
    case XmlRpc::XmlRpcValue::TypeString: return "a string";
    case XmlRpc::XmlRpcValue::TypeDateTime: return "a date";
    case XmlRpc::XmlRpcValue::TypeBase64: return "binary data";
    case XmlRpc::XmlRpcValue::TypeArray: return "a list";
    case XmlRpc::XmlRpcValue::TypeStruct: return "a map";
    default: return "invalid";
  }
}

// `value` as written in a YAML 1.2 document (strings quoted); 17 digits
// round-trip a double, 10 are for messages.
std::string yamlValue(XmlRpc::XmlRpcValue& v, int precision = 17) {
  std::ostringstream os;
  os.precision(precision);
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeInt: os << static_cast<int>(v); break;
    case XmlRpc::XmlRpcValue::TypeDouble: os << static_cast<double>(v); break;
    case XmlRpc::XmlRpcValue::TypeBoolean: os << (static_cast<bool>(v) ? "true" : "false"); break;
    default: {
      os << '"';
      for (char c : static_cast<std::string>(v)) {
        if (c == '"' || c == '\\') os << '\\';
        os << c;
      }
      os << '"';
    }
  }
  return os.str();
}

}  // namespace

std::string toYaml(const DoorStateConfig& config) {
  std::ostringstream os;
  os.precision(17);
  for (const auto& d : DoorStateConfig::__getParamDescriptions__()) {
    boost::any v;
    d->getValue(config, v);
    os << d->name << ": ";
    if (d->type == "double") os << boost::any_cast<double>(v);
    else if (d->type == "int") os << boost::any_cast<int>(v);
    else if (d->type == "bool") os << (boost::any_cast<bool>(v) ? "true" : "false");
    else os << '"' << boost::any_cast<std::string>(v) << '"';
    os << "\n";
  }
  return os.str();
}

std::string nonFinite(const DoorStateConfig& config) {
  std::string bad;
  for (const auto& d : DoorStateConfig::__getParamDescriptions__()) {
    if (d->type != "double") continue;
    boost::any v;
    d->getValue(config, v);
    const double x = boost::any_cast<double>(v);
    if (!std::isfinite(x)) bad += (bad.empty() ? "" : ", ") + d->name + " = " + (std::isnan(x) ? "NaN" : "Inf");
  }
  return bad.empty() ? bad : "parameter " + bad + " is not a finite number";
}

std::vector<std::string> checkPrivateParameters(const ros::NodeHandle& pnh) {
  std::vector<std::string> problems;
  const std::string ns = pnh.getNamespace();
  XmlRpc::XmlRpcValue all;
  if (!pnh.getParam(ns, all)) return problems;  // nothing set: the defaults
  if (all.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    problems.push_back(ns + " is " + typeName(all) + ", not a namespace of parameters");
    return problems;
  }
  const DoorStateConfig lo = DoorStateConfig::__getMin__(), hi = DoorStateConfig::__getMax__();
  std::map<std::string, DoorStateConfig::AbstractParamDescriptionConstPtr> cfg;
  for (const auto& d : DoorStateConfig::__getParamDescriptions__()) cfg[d->name] = d;
  std::string yaml_all;  // every well-typed pipeline parameter, for the checks across parameters
  for (auto it = all.begin(); it != all.end(); ++it) {
    const std::string& name = it->first;
    XmlRpc::XmlRpcValue& v = it->second;
    const std::string pname = ns + "/" + name;
    const bool scalar = v.getType() == XmlRpc::XmlRpcValue::TypeInt || v.getType() == XmlRpc::XmlRpcValue::TypeDouble ||
                        v.getType() == XmlRpc::XmlRpcValue::TypeBoolean || v.getType() == XmlRpc::XmlRpcValue::TypeString;
    const std::string got = typeName(v) + (scalar ? " (" + yamlValue(v, 10) + ")" : std::string());
    // The nodelet's own.
    if (name == "fixed_frame") {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeString) problems.push_back(pname + " is " + got + ": must be a frame name (a string), empty for the cloud's own frame");
      continue;
    }
    if (name == "viewpoint") {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeString ||
          (static_cast<std::string>(v) != "sensor" && static_cast<std::string>(v) != "none"))
        problems.push_back(pname + " is " + got + ": must be 'sensor' (rays from the cloud frame's origin) or 'none' (a map: no viewpoint)");
      continue;
    }
    if (name == "tf_queue_size") {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeInt || static_cast<int>(v) < 1) problems.push_back(pname + " is " + got + ": must be an int >= 1");
      continue;
    }
    if (name == "forget_after_s") {
      if (!isNumber(v) || !(asDouble(v) > 0) || !std::isfinite(asDouble(v)))
        problems.push_back(pname + " is " + got + ": must be a number of seconds > 0");
      continue;
    }
    if (name == "max_sensor_speed") {
      if (!isNumber(v) || !(asDouble(v) >= 0) || !std::isfinite(asDouble(v)))
        problems.push_back(pname + " is " + got + ": must be a number of m/s >= 0 (0: no relocalisation check)");
      continue;
    }
    if (name == "confirm_clouds") {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeInt || static_cast<int>(v) < 1) problems.push_back(pname + " is " + got + ": must be an int >= 1");
      continue;
    }
    if (name == "withdraw_not_found") {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) problems.push_back(pname + " is " + got + ": must be a bool");
      continue;
    }
    if (name == "confirm_spread_m") {
      if (!isNumber(v) || !(asDouble(v) >= 0) || !std::isfinite(asDouble(v)))
        problems.push_back(pname + " is " + got + ": must be a number of metres >= 0");
      continue;
    }
    if (name == "state_change_deg") {
      if (!isNumber(v) || !(asDouble(v) > 0 && asDouble(v) <= 180))
        problems.push_back(pname + " is " + got + ": must be a number of degrees in (0, 180]");
      continue;
    }
    if (name == "diagnostic_period") {  // read by diagnostic_updater::Updater
      if (!isNumber(v) || !(asDouble(v) > 0)) problems.push_back(pname + " is " + got + ": must be a number of seconds > 0");
      continue;
    }
    const auto c = cfg.find(name);
    if (c == cfg.end()) {
      problems.push_back(pname + ": unknown parameter (the pipeline's are those of config/default.yaml; the nodelet's own are fixed_frame, viewpoint, tf_queue_size, diagnostic_period, forget_after_s, state_change_deg, max_sensor_speed, confirm_clouds, confirm_spread_m, withdraw_not_found)");
      continue;
    }
    const std::string& type = c->second->type;
    boost::any amin, amax;
    c->second->getValue(lo, amin);
    c->second->getValue(hi, amax);
    std::ostringstream range;
    range.precision(10);
    bool ok_type = false, in_cfg = true;
    if (type == "double") {
      ok_type = isNumber(v);
      const double a = boost::any_cast<double>(amin), b = boost::any_cast<double>(amax);
      if (ok_type) {
        const double x = asDouble(v);
        in_cfg = std::isfinite(x) && x >= a && x <= b;
      }
      range << "a number in [" << a << ", " << b << "]";
    } else if (type == "int") {
      ok_type = v.getType() == XmlRpc::XmlRpcValue::TypeInt;
      const int a = boost::any_cast<int>(amin), b = boost::any_cast<int>(amax);
      if (ok_type) in_cfg = static_cast<int>(v) >= a && static_cast<int>(v) <= b;
      range << "an int in [" << a << ", " << b << "]";
    } else if (type == "str") {
      ok_type = v.getType() == XmlRpc::XmlRpcValue::TypeString;
      range << "a string";
    } else if (type == "bool") {
      ok_type = v.getType() == XmlRpc::XmlRpcValue::TypeBoolean;
      range << "true or false";
    }
    if (!ok_type) {
      std::string hint;
      if (v.getType() == XmlRpc::XmlRpcValue::TypeString && type != "str")
        hint = " (YAML 1.1, as rosparam and roslaunch read it, takes a number with an exponent and no dot, e.g. 2e-2, as a string: write 2.0e-2 or 0.02)";
      problems.push_back(pname + " is " + got + ": must be " + range.str() + hint);
      continue;
    }
    if (type == "double" && !std::isfinite(asDouble(v))) {
      problems.push_back(pname + " is " + got + ": must be " + range.str() + ", a finite number");
      continue;
    }
    const std::string line = name + ": " + yamlValue(v) + "\n";
    // The pipeline's own range first (it is the narrower one where they differ), then the .cfg's.
    try {
      dsr::parseParameters(line, dsr::Parameters(), pname);
    } catch (const std::exception& e) {
      problems.push_back(std::string(e.what()) + " (given " + yamlValue(v, 10) + ")");
      continue;
    }
    if (!in_cfg) {
      problems.push_back(pname + " = " + yamlValue(v, 10) + " out of range: must be " + range.str() +
                         " (the range of cfg/DoorState.cfg; dynamic_reconfigure would clamp it)");
      continue;
    }
    yaml_all += line;
  }
  if (problems.empty()) {
    try {
      dsr::parseParameters(yaml_all, dsr::Parameters(), ns);  // e.g. door_min_width above door_max_width
    } catch (const std::exception& e) {
      problems.push_back(e.what());
    }
  }
  return problems;
}

std::string atRangeEnd(const DoorStateConfig& config, const DoorStateConfig& before) {
  const DoorStateConfig lo = DoorStateConfig::__getMin__(), hi = DoorStateConfig::__getMax__();
  std::ostringstream os;
  os.precision(10);
  bool any = false;
  for (const auto& d : DoorStateConfig::__getParamDescriptions__()) {
    if (d->type != "double" && d->type != "int") continue;
    boost::any v, b, a, z;
    d->getValue(config, v);
    d->getValue(before, b);
    d->getValue(lo, a);
    d->getValue(hi, z);
    auto num = [&](const boost::any& x) { return d->type == "double" ? boost::any_cast<double>(x) : boost::any_cast<int>(x); };
    const double x = num(v);
    if (x == num(b) || (x != num(a) && x != num(z))) continue;
    os << (any ? ", " : "") << d->name << " = " << x << " (the " << (x == num(a) ? "lower" : "upper") << " end of ["
       << num(a) << ", " << num(z) << "])";
    any = true;
  }
  return os.str();
}

}  // namespace door_state_recognition
