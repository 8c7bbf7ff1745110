"""The model wing: modal beam, quadrature, contact law and the CasADi assembly of
``M(x, p) xdot = F(x, p)`` for one scene structure (Scene -> Model)."""

from .assembly import Model, build_model, modal_basis, parameter_names
from .beam import ModalBasis, clamped_free_betas, clamped_free_modes
from .codegen import compile_function, compile_model
from .fields import FlowFields, flow_fields

__all__ = ["Model", "build_model", "modal_basis", "parameter_names", "ModalBasis",
           "clamped_free_betas", "clamped_free_modes", "compile_function", "compile_model",
           "FlowFields", "flow_fields"]
