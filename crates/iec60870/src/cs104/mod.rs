//! IEC 104 stations.
