//! The Sparkplug B topic namespace: `spBv1.0/{group}/{type}/{edge node}[/{device}]` and a
//! host application's `spBv1.0/STATE/{host}`.

/// The namespace of Sparkplug B.
pub const NAMESPACE: &str = "spBv1.0";

/// What a message is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MessageType {
    /// Node birth.
    NBirth,
    /// Node death.
    NDeath,
    /// Node data.
    NData,
    /// Node command.
    NCmd,
    /// Device birth.
    DBirth,
    /// Device death.
    DDeath,
    /// Device data.
    DData,
    /// Device command.
    DCmd,
}

impl MessageType {
    /// The topic element.
    pub fn as_str(self) -> &'static str {
        match self {
            MessageType::NBirth => "NBIRTH",
            MessageType::NDeath => "NDEATH",
            MessageType::NData => "NDATA",
            MessageType::NCmd => "NCMD",
            MessageType::DBirth => "DBIRTH",
            MessageType::DDeath => "DDEATH",
            MessageType::DData => "DDATA",
            MessageType::DCmd => "DCMD",
        }
    }

    fn parse(text: &str) -> Option<MessageType> {
        Some(match text {
            "NBIRTH" => MessageType::NBirth,
            "NDEATH" => MessageType::NDeath,
            "NDATA" => MessageType::NData,
            "NCMD" => MessageType::NCmd,
            "DBIRTH" => MessageType::DBirth,
            "DDEATH" => MessageType::DDeath,
            "DDATA" => MessageType::DData,
            "DCMD" => MessageType::DCmd,
            _ => return None,
        })
    }

    /// Whether the message is about a device (its topic names one).
    pub fn is_device(self) -> bool {
        matches!(
            self,
            MessageType::DBirth | MessageType::DDeath | MessageType::DData | MessageType::DCmd
        )
    }
}

/// A Sparkplug topic.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Topic {
    /// A message of an edge node or one of its devices.
    Node {
        /// The group id.
        group: String,
        /// The message type.
        message: MessageType,
        /// The edge node id.
        edge_node: String,
        /// The device id (device messages only).
        device: Option<String>,
    },
    /// A host application's state.
    State {
        /// The host id.
        host: String,
    },
}

/// Why a topic is not a Sparkplug B one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("not a Sparkplug B topic: `{0}`")]
pub struct TopicError(pub String);

impl Topic {
    /// A node message's topic.
    pub fn node(group: &str, message: MessageType, edge_node: &str) -> Topic {
        Topic::Node {
            group: group.to_owned(),
            message,
            edge_node: edge_node.to_owned(),
            device: None,
        }
    }

    /// Parses a topic received from the broker.
    pub fn parse(topic: &str) -> Result<Topic, TopicError> {
        let bad = || TopicError(topic.to_owned());
        let parts: Vec<&str> = topic.split('/').collect();
        match parts.as_slice() {
            [NAMESPACE, "STATE", host] if valid_id(host) => Ok(Topic::State {
                host: (*host).to_owned(),
            }),
            [NAMESPACE, group, message, edge_node, rest @ ..]
                if valid_id(group) && valid_id(edge_node) =>
            {
                let message = MessageType::parse(message).ok_or_else(bad)?;
                let device = match (message.is_device(), rest) {
                    (false, []) => None,
                    (true, [device]) if valid_id(device) => Some((*device).to_owned()),
                    _ => return Err(bad()),
                };
                Ok(Topic::Node {
                    group: (*group).to_owned(),
                    message,
                    edge_node: (*edge_node).to_owned(),
                    device,
                })
            }
            _ => Err(bad()),
        }
    }
}

/// Whether an id may stand in a topic: not empty, no MQTT separator or wildcard.
pub fn valid_id(id: &str) -> bool {
    !id.is_empty() && !id.contains(['/', '+', '#'])
}

impl std::fmt::Display for Topic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Topic::Node {
                group,
                message,
                edge_node,
                device,
            } => {
                write!(f, "{NAMESPACE}/{group}/{}/{edge_node}", message.as_str())?;
                if let Some(device) = device {
                    write!(f, "/{device}")?;
                }
                Ok(())
            }
            Topic::State { host } => write!(f, "{NAMESPACE}/STATE/{host}"),
        }
    }
}
