"""
A node's services on a DDS participant of their own, so that a flood of its inputs loses none.

rmw_fastrtps gives each rclpy context one DDS participant, and every message for the
participant arrives through the same receive queues (its shared-memory port, its UDP
sockets). A publisher flooding one input faster than the node takes it fills those queues;
what arrives meanwhile is dropped — a best-effort input is then simply lost, but a service
request is reliable and comes again only at its client's next DDS heartbeat (3 s with Fast
DDS's defaults). Under a back-to-back flood about 1 % of the calls took 1.5–3 s that way
(bench/README.md, "Overload"). :class:`ServiceHost` serves a node's services — its own and
the parameter services — from a hidden node in a second context: a participant whose
queues carry nothing but requests.

Names and behaviour are unchanged for callers: the services keep the names the node would
give them (``~/describe`` resolved by the node, remappings included), the parameter
services still act on the node's parameters, and the node itself stays in the graph (the
hidden one, ``<node>/_services``, is listed only by ``ros2 node list -a``). Its fully
qualified name is the node's plus 10 characters, fewer than the node's parameter service
names add, so every name rclpy accepted for the node is valid for it. The hidden node is
one of the node's ``companions``: rot_tools.ros.runtime.spin guards its callbacks and spins it
on the node's executor (one wait set takes entities of both contexts).
"""

from rcl_interfaces.srv import DescribeParameters, GetParameters, GetParameterTypes
from rcl_interfaces.srv import ListParameters, SetParameters, SetParametersAtomically
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_service import ParameterService
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM

PARAMETER_SERVICE_TYPES = (DescribeParameters, GetParameters, GetParameterTypes,
                           ListParameters, SetParameters, SetParametersAtomically)
"""The types of the six parameter services rclpy.parameter_service.ParameterService serves."""

NO_TYPE_DESCRIPTION_SERVICE = Parameter(START_TYPE_DESCRIPTION_SERVICE_PARAM, value=False)
"""The hidden node has no ~/get_type_description (the owner's describes the types)."""


class ServiceHost:
    """
    Creates ``owner``'s services on a hidden node of a context of its own.

    The owner's parameter services, if rclpy started them (``start_parameter_services``,
    whose names rclpy validates while building the node), are destroyed: the host serves
    them. Everything else asked of the host is the owner's (the parameter services read and
    set the owner's parameters through it).
    """

    def __init__(self, owner):
        self._owner = owner
        for srv in list(owner.services):
            if srv.srv_type in PARAMETER_SERVICE_TYPES:
                owner.destroy_service(srv)
        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context)
        try:
            self.node = Node(
                '_services', namespace=owner.get_fully_qualified_name(),
                context=self.context, use_global_arguments=False,
                start_parameter_services=False, enable_rosout=False,
                parameter_overrides=[NO_TYPE_DESCRIPTION_SERVICE])
        except Exception:
            self.context.try_shutdown()
            raise
        self._parameter_service = ParameterService(self)

    def create_service(self, srv_type, name, callback, **kwargs):
        """Serve ``name`` (resolved as the owner resolves it) from the hidden node."""
        return self.node.create_service(
            srv_type, self._owner.resolve_service_name(name), callback, **kwargs)

    def __getattr__(self, name):
        return getattr(self._owner, name)

    def destroy(self):
        """Destroy the hidden node and its context (its participant leaves the graph now)."""
        self.node.destroy_node()
        self.context.try_shutdown()
        self.context.destroy()
