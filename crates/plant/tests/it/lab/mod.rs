//! The teaching-lab models: bindings, each model's checklist of the spec's section 8,
//! step-size independence and random operation sequences.

mod bindings;
