// The native C++ library as a ROS node (roscpp), linked directly: no Python on this side.
//
//   rrosfuzz_native_node --urdf ROBOT.urdf --name NAME [--tip-link LINK]
//
// Protocol (fuzzer/ros/transport.py, docs/engine.md "The ROS transport"): std_msgs/String on
// /rrosfuzz/<name>/{ready,request,response}; a request is "<id>\n<JSON>", the JSON being
// {"op": "run", "call": call_to_json(call, seed)}, {"op": "fresh"} or {"op": "ping"}; the answer is
// "<id>\n{"id": id, "outcome": ...}" with the outcome of fuzzer.targets.Runner.run. Non-finite
// floats travel as {"$float": "nan" | "inf" | "-inf"}. A rejected call's outcome carries the
// contract's code only; the engine names its class (robot_api.errors.error_class).
#include <ros/ros.h>
#include <std_msgs/String.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

#include "constants.hpp"
#include "errors.hpp"
#include "model.hpp"
#include "move_group.hpp"

using json = nlohmann::json;
using rrosfuzz::ApiError;
using rrosfuzz::ErrorCode;
using rrosfuzz::Model;
using rrosfuzz::MoveGroup;

namespace {

json number(double v) {
  if (std::isnan(v)) return json{{"$float", "nan"}};
  if (std::isinf(v)) return json{{"$float", v > 0 ? "inf" : "-inf"}};
  return v;
}

double to_double(const json& j, const char* what) {
  if (j.is_number()) return j.get<double>();
  if (j.is_object() && j.contains("$float") && j["$float"].is_string()) {
    const std::string s = j["$float"];
    if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
    if (s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-inf") return -std::numeric_limits<double>::infinity();
  }
  throw std::invalid_argument(std::string("request field ") + what + " is not a number");
}

std::vector<double> to_doubles(const json& j, const char* what) {
  if (!j.is_array()) throw std::invalid_argument(std::string("request field ") + what + " is not a list");
  std::vector<double> out;
  for (const auto& v : j) out.push_back(to_double(v, what));
  return out;
}

std::optional<std::string> to_link(const json& j) {
  if (j.is_null()) return std::nullopt;
  if (!j.is_string()) throw std::invalid_argument("request field link is not a string");
  return j.get<std::string>();
}

json numbers(const std::vector<double>& v) {
  json out = json::array();
  for (double x : v) out.push_back(number(x));
  return out;
}

void put_pose(json& values, const KDL::Frame& f) {
  double q[4];
  rrosfuzz::canonical_quaternion(f.M, q);
  values["position"] = json::array({number(f.p.x()), number(f.p.y()), number(f.p.z())});
  values["orientation"] = json::array({number(q[0]), number(q[1]), number(q[2]), number(q[3])});
}

json outcome(const char* status, const json& values = json::object()) {
  return json{{"status", status}, {"error", ""}, {"code", nullptr}, {"message", ""}, {"values", values}};
}

json crashed(const std::string& error, const std::string& message) {
  json o = outcome("crashed");
  o["error"] = error;
  o["message"] = message.substr(0, 500);
  return o;
}

// What fuzzer.targets.Runner.run does with native's Python binding, in C++.
json run(const std::shared_ptr<Model>& model, const json& call) {
  const std::string kind = call.value("kind", "");
  json values = json::object();
  if (kind == "FkCall") {
    const auto q = to_doubles(call.at("joint_values"), "joint_values");
    model->check_joint_vector(q, "joint values");
    const int link = model->link_index(to_link(call.value("link", json())));
    put_pose(values, model->fk(q, link));
    return outcome("ok", values);
  }
  if (kind == "IkCall") {
    const auto p = to_doubles(call.at("position"), "position");
    const auto o = to_doubles(call.at("orientation"), "orientation");
    if (p.size() != 3) rrosfuzz::fail(ErrorCode::kInvalidArgument, "pose position: expected 3 values");
    if (o.size() != 4) rrosfuzz::fail(ErrorCode::kInvalidArgument, "pose orientation: expected 4 values (x, y, z, w)");
    for (double v : p) {
      if (!std::isfinite(v)) rrosfuzz::fail(ErrorCode::kNonFinite, "pose position is not finite");
    }
    for (double v : o) {
      if (!std::isfinite(v)) rrosfuzz::fail(ErrorCode::kNonFinite, "pose orientation is not finite");
    }
    const double scale = std::max({std::fabs(o[0]), std::fabs(o[1]), std::fabs(o[2]), std::fabs(o[3])});
    const double x = scale > 0.0 ? o[0] / scale : 0.0, y = scale > 0.0 ? o[1] / scale : 0.0;
    const double z = scale > 0.0 ? o[2] / scale : 0.0, w = scale > 0.0 ? o[3] / scale : 0.0;
    const double unit = std::sqrt(x * x + y * y + z * z + w * w);
    if (!(scale * unit >= rrosfuzz::kQuaternionNormEps)) {
      rrosfuzz::fail(ErrorCode::kInvalidArgument, "pose orientation: quaternion has (near) zero norm");
    }
    const KDL::Frame target(KDL::Rotation::Quaternion(x / unit, y / unit, z / unit, w / unit),
                            KDL::Vector(p[0], p[1], p[2]));
    std::vector<double> seed = model->home();
    if (call.contains("seed") && !call["seed"].is_null()) {
      seed = to_doubles(call["seed"], "seed");
      model->check_joint_vector(seed, "seed");
    }
    const int link = model->link_index(to_link(call.value("link", json())));
    const auto answer = model->ik(target, seed, link);
    model->check_joint_vector(answer.joint_values, "joint values");
    values["joint_values"] = numbers(answer.joint_values);
    put_pose(values, model->fk(answer.joint_values, link));
    return outcome(answer.status == rrosfuzz::IkStatus::kSuccess ? "ok" : "failed", values);
  }
  if (kind == "MoveCall") {
    MoveGroup group(model);
    if (call.contains("velocity_scaling") && !call["velocity_scaling"].is_null()) {
      group.set_velocity_scaling(to_double(call["velocity_scaling"], "velocity_scaling"));
    }
    if (call.contains("acceleration_scaling") && !call["acceleration_scaling"].is_null()) {
      group.set_acceleration_scaling(to_double(call["acceleration_scaling"], "acceleration_scaling"));
    }
    const auto positions = to_doubles(call.at("positions"), "positions");
    if (!call.contains("names") || call["names"].is_null()) {
      group.set_target(positions);
    } else {
      group.set_target(call["names"].get<std::vector<std::string>>(), positions);
    }
    const bool moved = group.go();
    values["joint_values"] = numbers(group.current());
    put_pose(values, model->fk(group.current(), model->link_index(std::nullopt)));
    return outcome(moved ? "ok" : "failed", values);
  }
  throw std::invalid_argument("unknown call kind '" + kind + "'");
}

struct Node {
  std::string urdf;
  std::optional<std::string> tip;
  std::shared_ptr<Model> model;
  ros::Publisher response;
  std::string engine;  // the engine's node name (--engine): requests of other nodes are ignored

  // Called by ros::spin() on this (the only) thread, one request at a time. The ROS graph may be
  // shared: any node may publish on the request topic.
  void on_request(const ros::MessageEvent<std_msgs::String const>& event) {
    if (!engine.empty() && event.getPublisherName() != engine) return;
    serve_one(event.getMessage()->data);
  }

  json answer(const json& request) {
    try {
      if (request.value("op", "") == "ping") return outcome("ok");
      if (request.value("op", "") == "fresh") {
        model = std::make_shared<Model>(urdf, true, tip);
        return outcome("ok");
      }
      return run(model, request.at("call"));
    } catch (const ApiError& e) {
      json o = outcome("rejected");
      o["code"] = static_cast<int>(e.code());
      o["message"] = std::string(e.what()).substr(0, 500);
      return o;
    } catch (const std::bad_alloc& e) {  // pybind11's translations of the standard exceptions
      return crashed("MemoryError", e.what());
    } catch (const std::out_of_range& e) {
      return crashed("IndexError", e.what());
    } catch (const std::invalid_argument& e) {
      return crashed("ValueError", e.what());
    } catch (const std::domain_error& e) {
      return crashed("ValueError", e.what());
    } catch (const json::exception& e) {
      return crashed("BadRequest", e.what());
    } catch (const std::exception& e) {
      return crashed("RuntimeError", e.what());
    }
  }

  void serve_one(const std::string& data) {
    const auto newline = data.find('\n');
    if (newline == std::string::npos) return;
    const long id = std::strtol(data.substr(0, newline).c_str(), nullptr, 10);
    json result;
    try {
      result = answer(json::parse(data.substr(newline + 1)));
    } catch (const json::exception& e) {
      result = crashed("BadRequest", e.what());
    }
    std_msgs::String out;
    out.data = std::to_string(id) + "\n" + json{{"id", id}, {"outcome", result}}.dump();
    response.publish(out);
  }
};

std::string argument(int argc, char** argv, const std::string& name, bool required) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (argv[i] == name) return argv[i + 1];
  }
  if (required) {
    std::fprintf(stderr,
                 "usage: rrosfuzz_native_node --urdf FILE --name NAME [--tip-link LINK] [--engine NODE]\n");
    std::exit(2);
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  const std::string name = argument(argc, argv, "--name", true);
  Node node;
  node.urdf = argument(argc, argv, "--urdf", true);
  const std::string tip = argument(argc, argv, "--tip-link", false);
  if (!tip.empty()) node.tip = tip;
  node.engine = argument(argc, argv, "--engine", false);
  ros::init(argc, argv, "rrosfuzz_" + name, ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
  ros::NodeHandle handle;
  const std::string topic = "/rrosfuzz/" + name;
  ros::Publisher ready = handle.advertise<std_msgs::String>(topic + "/ready", 1, true);
  node.response = handle.advertise<std_msgs::String>(topic + "/response", 10);
  json facts{{"pid", static_cast<long>(getpid())}, {"spec", "native_cpp"}, {"error", ""}};
  try {
    node.model = std::make_shared<Model>(node.urdf, true, node.tip);
  } catch (const std::exception& e) {
    facts["error"] = std::string("RobotModel: ") + e.what();
    std_msgs::String message;
    message.data = facts.dump();
    ready.publish(message);
    ros::Duration(1.0).sleep();
    return 1;
  }
  json names = json::array();
  for (const auto& v : node.model->variables()) names.push_back(v.name);
  facts["joint_names"] = names;
  ros::Subscriber requests = handle.subscribe(topic + "/request", 10, &Node::on_request, &node);
  std_msgs::String message;
  message.data = facts.dump();
  ready.publish(message);
  ros::spin();
  return 0;
}
