//! Helpers shared by the fibre node's integration tests: configure a fibre component
//! alone on an in-process exchange, or read the message it refuses a scene with.
use cosim::{Component, InProcessExchange};
use fibre_node::FibreComponent;

pub fn configured(scene: &str) -> (FibreComponent, InProcessExchange) {
    let mut c = FibreComponent::new();
    let mut x = InProcessExchange::new();
    c.configure(scene, &mut x).unwrap_or_else(|e| panic!("{e}"));
    (c, x)
}

pub fn configure_error(scene: &str) -> String {
    let mut x = InProcessExchange::new();
    match FibreComponent::new().configure(scene, &mut x) {
        Ok(_) => panic!("configure accepted a scene it should refuse"),
        Err(e) => e.to_string(),
    }
}
