"""ROS 2 messages and services, imported as in rclpy: `from llfsm.msgs.geometry_msgs.msg import Twist`.

Built in (generated modules, committed): builtin_interfaces, std_msgs, geometry_msgs, std_srvs,
turtlesim and turtle_sensor_interface.  A user's own interfaces, folders PKG/msg/*.msg and
PKG/srv/*.srv in ROS layout, import the same way (`from llfsm.msgs.my_pkg.srv import Foo`)
through an import hook that searches `search_path()` and compiles them into the cache.
Importing this package stays light: it loads no parser, template engine or YAML library.
"""

from __future__ import annotations

from ._finder import add_search_path, find_package, install, search_path
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
