"""The LAV-like stack's channel names (one definition, for the stack and for replay)."""

TOPIC_EGO = "/lav/gnss/ego"
TOPIC_AGENTS = "/lav/pnp/agents"
TOPIC_PLAN = "/lav/planner/waypoints"
TOPIC_BRAKE = "/lav/brake/prediction"
TOPIC_COMMAND = "/lav/control/command"
