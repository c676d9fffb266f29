#include "implicit_sim/ros/master_watch.h"

#include <ros/connection_manager.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <ros/service_manager.h>
#include <ros/xmlrpc_manager.h>
#include <xmlrpcpp/XmlRpcClient.h>

namespace implicit_sim {
namespace {

// The master's pid; false when it does not answer. A client of its own: ros::master::execute retries until the master
// answers, which would hold the diagnostics thread.
bool MasterPid(int* pid) {
  XmlRpc::XmlRpcClient client(ros::master::getHost().c_str(), static_cast<int>(ros::master::getPort()), "/");
  XmlRpc::XmlRpcValue args, result;
  args[0] = ros::this_node::getName();
  if (!client.execute("getPid", args, result) || result.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      result.size() < 3 || result[2].getType() != XmlRpc::XmlRpcValue::TypeInt) {
    return false;
  }
  *pid = static_cast<int>(result[2]);
  return true;
}

// This node's publications or subscriptions as [[topic, type], ...], from its own slave API.
bool OwnTopics(const char* method, XmlRpc::XmlRpcValue* topics) {
  std::string host;
  uint32_t port = 0;
  if (!ros::network::splitURI(ros::XMLRPCManager::instance()->getServerURI(), host, port)) return false;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue args, result;
  args[0] = ros::this_node::getName();
  if (!client.execute(method, args, result) || result.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      result.size() < 3) {
    return false;
  }
  *topics = result[2];
  return topics->getType() == XmlRpc::XmlRpcValue::TypeArray;
}

bool Register(const char* method, const std::string& name, const std::string& second) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = name;
  args[2] = second;
  args[3] = ros::XMLRPCManager::instance()->getServerURI();
  return ros::master::execute(method, args, result, payload, false);
}

}  // namespace

MasterWatch::MasterWatch(Policy policy, std::function<std::vector<std::string>()> service_names)
    : policy_(policy), service_names_(std::move(service_names)) {
  MasterPid(&known_pid_);  // the master the node registered with
}

bool MasterWatch::Check() {
  if (exit_requested_) return false;
  int pid = -1;
  const bool up = MasterPid(&pid);
  if (up && pid == known_pid_) return true;
  if (!lost_) {
    lost_ = true;
    ROS_ERROR("implicit_sim: lost the ROS master at %s (%s); %s", ros::master::getURI().c_str(),
              up ? "it was restarted and does not know this node" : "it does not answer",
              policy_ == Policy::kExit ? "exiting (~on_master_loss: exit)"
                                       : "stepping on, and registering again when a master answers "
                                         "(~on_master_loss: reregister)");
  }
  if (policy_ == Policy::kExit) {
    exit_requested_ = true;
    ros::requestShutdown();
    return false;
  }
  if (!up) return true;
  if (Reregister()) {
    known_pid_ = pid;
    lost_ = false;
  }
  return true;
}

bool MasterWatch::Reregister() {
  XmlRpc::XmlRpcValue publications, subscriptions;
  if (!OwnTopics("getPublications", &publications) || !OwnTopics("getSubscriptions", &subscriptions)) return false;
  bool ok = true;
  int topics = 0, services = 0;
  for (int i = 0; i < publications.size(); ++i, ++topics) {
    ok &= Register("registerPublisher", publications[i][0], publications[i][1]);
  }
  for (int i = 0; i < subscriptions.size(); ++i, ++topics) {
    ok &= Register("registerSubscriber", subscriptions[i][0], subscriptions[i][1]);
  }
  const std::string service_uri = "rosrpc://" + ros::network::getHost() + ":" +
                                  std::to_string(ros::ConnectionManager::instance()->getTCPPort());
  for (const std::string& name : service_names_()) {
    if (!ros::ServiceManager::instance()->lookupServicePublication(name)) continue;
    XmlRpc::XmlRpcValue args, result, payload;
    args[0] = ros::this_node::getName();
    args[1] = name;
    args[2] = service_uri;
    args[3] = ros::XMLRPCManager::instance()->getServerURI();
    ok &= ros::master::execute("registerService", args, result, payload, false);
    ++services;
  }
  if (ok) {
    ROS_INFO("implicit_sim: registered %d topics and %d services with the ROS master at %s again", topics, services,
             ros::master::getURI().c_str());
  }
  return ok;
}

}  // namespace implicit_sim
