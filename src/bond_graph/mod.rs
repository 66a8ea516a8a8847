//! Bond-graph core. (Being written: issue "Bond-graph core".)
