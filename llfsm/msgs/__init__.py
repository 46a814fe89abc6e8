"""ROS 2 messages and services, imported as in rclpy: `from llfsm.msgs.geometry_msgs.msg import Twist`
(docs/bus.md, "Messages").

Shipped (generated modules, committed, from the definitions in _interfaces/): builtin_interfaces,
std_msgs, geometry_msgs, std_srvs, sensor_msgs, nav_msgs, turtlesim, turtle_sensor_interface,
service_msgs, rmw_dds_common and rcl_interfaces.  A user's own interfaces, folders
PKG/msg/*.msg and PKG/srv/*.srv in ROS layout, import the same way (`from llfsm.msgs.my_pkg.srv
import Foo`) through an import hook that searches `search_path()` and compiles them into the
cache.  Importing this package stays light:
it loads no parser, template engine or YAML library.
"""

from __future__ import annotations

from ..interface_path import add_search_path, find_package, search_path
from ._finder import install
from ._message import Message, Service, is_message_class, is_service_class
from ._yaml import to_yaml

__all__ = [
    "Message",
    "Service",
    "add_search_path",
    "find_package",
    "is_message_class",
    "is_service_class",
    "search_path",
    "to_yaml",
]

install()
