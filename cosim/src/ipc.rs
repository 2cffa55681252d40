//! iceoryx2 transport: control by request-response, bulk data by publish-subscribe.
//! (Being written; see the module docs once it lands.)
