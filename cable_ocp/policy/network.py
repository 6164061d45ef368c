"""The policy's network: a small tanh MLP with its normalisation, in numpy and in CasADi.

``action = clip(m_y + s_y * (W_L tanh(... tanh(W_1 (x - m_x) / s_x + b_1) ...) + b_L), -a, a)``:
the observation ``x`` normalised by its training mean ``m_x`` and spread ``s_x``, hidden layers of
``tanh``, a linear output scaled back to rad/s, and the drum rate clipped to the winch's
``rate_max`` ``a``, as the plant clips any command. :meth:`Network.fit` trains it by L-BFGS
(SciPy) on the mean squared error with an analytic gradient (backpropagation in numpy), from
weights drawn by a seeded generator, so that one seed gives one network, bit for bit, on one
machine.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.policy.defaults import ITERATIONS

# Weight decay on the normalised problem: enough to keep the weights finite where a feature
# never varied in the data, too little to bias the fit (the loss is about 1e-2 to 1e-4).
DECAY = 1e-6
# A feature whose spread in the data is below this (in its unit) is taken as constant: its scale
# is 1, so that a scene where it varies shows up outside the envelope, not as a division by 0.
SPREAD_FLOOR = 1e-9


@dataclass(frozen=True, eq=False)
class Network:
    """A tanh MLP from an observation to a drum rate (module docstring).

    Attributes
    ----------
    weights : tuple of arrays
        ``W_1 (h_1, d), ..., W_L (1, h_{L-1})``.
    biases : tuple of arrays
        ``b_1 (h_1,), ..., b_L (1,)``.
    input_mean, input_scale : arrays (d,), the observation's units
        The observation's normalisation, from the training data.
    output_mean, output_scale : float, rad/s
        The action's normalisation.
    rate_limit : float, rad/s
        The drum rate is clipped to ``[-rate_limit, rate_limit]`` (the winch's ``rate_max``).
    """

    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]
    input_mean: np.ndarray
    input_scale: np.ndarray
    output_mean: float
    output_scale: float
    rate_limit: float

    def __post_init__(self):
        if len(self.weights) != len(self.biases) or not self.weights:
            raise ValueError("network: as many bias vectors as weight matrices, at least one")
        width = self.input_mean.size
        if self.input_scale.shape != (width,) or np.any(self.input_scale <= 0):
            raise ValueError(f"network: input_scale must be {width} positive numbers")
        for k, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if w.ndim != 2 or w.shape[1] != width or b.shape != (w.shape[0],):
                raise ValueError(
                    f"network: layer {k} has weights {w.shape} and biases {b.shape} after a "
                    f"layer of {width}"
                )
            width = w.shape[0]
        if width != 1:
            raise ValueError(f"network: the last layer gives {width} values, not one drum rate")
        numbers = [*self.weights, *self.biases, self.input_mean, self.input_scale]
        scalars = np.array([self.output_mean, self.output_scale, self.rate_limit])
        if not all(np.isfinite(a).all() for a in numbers) or not np.isfinite(scalars).all():
            raise ValueError("network: a weight, bias or normalisation is not finite")
        if self.output_scale <= 0 or self.rate_limit <= 0:
            raise ValueError("network: output_scale and rate_limit must be positive")

    @property
    def inputs(self) -> int:
        """Length of the observation."""
        return int(self.input_mean.size)

    @property
    def hidden(self) -> tuple[int, ...]:
        """Widths of the hidden layers."""
        return tuple(int(w.shape[0]) for w in self.weights[:-1])

    def raw(self, observations: np.ndarray) -> np.ndarray:
        """The unclipped drum rate (rad/s) of each observation (rows of ``observations``)."""
        layer = (np.atleast_2d(observations) - self.input_mean) / self.input_scale
        for w, b in zip(self.weights[:-1], self.biases[:-1], strict=True):
            layer = np.tanh(layer @ w.T + b)
        out = layer @ self.weights[-1].T + self.biases[-1]
        return self.output_mean + self.output_scale * out[:, 0]

    def __call__(self, observations: np.ndarray) -> np.ndarray:
        """The drum rate (rad/s) of each observation, clipped to the winch's rate limit."""
        return np.clip(self.raw(observations), -self.rate_limit, self.rate_limit)

    def function(self) -> ca.Function:
        """The same network as a CasADi Function ``policy(observation) -> rate`` (SX)."""
        x = ca.SX.sym("observation", self.inputs)
        layer = (x - ca.DM(self.input_mean)) / ca.DM(self.input_scale)
        for w, b in zip(self.weights[:-1], self.biases[:-1], strict=True):
            layer = ca.tanh(ca.mtimes(ca.DM(w), layer) + ca.DM(b))
        out = ca.mtimes(ca.DM(self.weights[-1]), layer) + ca.DM(self.biases[-1])
        rate = self.output_mean + self.output_scale * out
        clipped = ca.fmin(ca.fmax(rate, -self.rate_limit), self.rate_limit)
        return ca.Function("policy", [x], [clipped], ["observation"], ["rate"])

    @classmethod
    def fit(
        cls,
        observations: np.ndarray,
        actions: np.ndarray,
        hidden: tuple[int, ...],
        rate_limit: float,
        seed: int,
        iterations: int = ITERATIONS,
    ) -> tuple[Network, float]:
        """Train a network on (observation, action) pairs by L-BFGS; it and its final loss.

        Parameters
        ----------
        observations : array (N, d)
        actions : array (N,), rad/s
        hidden : tuple of int
            Widths of the hidden layers.
        rate_limit : float, rad/s
        seed : int
            Seeds the initial weights (Glorot uniform); the fit is deterministic from there.
        iterations : int
            Most L-BFGS iterations.

        Returns
        -------
        (Network, float)
            The network and its mean squared error on the data, in the normalised action
            (1 is as good as predicting the mean).
        """
        from scipy.optimize import minimize

        x = np.asarray(observations, dtype=float)
        y = np.asarray(actions, dtype=float)
        if x.ndim != 2 or y.shape != (x.shape[0],) or x.shape[0] < 2:
            raise ValueError(
                f"fit: observations {x.shape} and actions {y.shape}: expected (N, d) and (N,), "
                "N >= 2"
            )
        if not (np.isfinite(x).all() and np.isfinite(y).all()):
            raise ValueError("fit: an observation or an action is not finite")
        if not hidden or any(isinstance(h, bool) or int(h) != h or h < 1 for h in hidden):
            raise ValueError(f"fit: hidden = {hidden!r}: expected widths >= 1")
        mean_x, scale_x = x.mean(axis=0), x.std(axis=0)
        scale_x = np.where(scale_x > SPREAD_FLOOR, scale_x, 1.0)
        mean_y, scale_y = float(y.mean()), float(y.std())
        scale_y = scale_y if scale_y > SPREAD_FLOOR else 1.0
        xn, yn = (x - mean_x) / scale_x, (y - mean_y) / scale_y
        shapes = _shapes(x.shape[1], tuple(int(h) for h in hidden))
        rng = np.random.default_rng(seed)
        start = np.concatenate(
            [
                part
                for rows, columns in shapes
                for part in (
                    rng.uniform(-1, 1, rows * columns) * np.sqrt(6.0 / (rows + columns)),
                    np.zeros(rows),
                )
            ]
        )
        found = minimize(
            _loss,
            start,
            args=(xn, yn, shapes),
            jac=True,
            method="L-BFGS-B",
            options={"maxiter": iterations, "maxfun": 2 * iterations, "ftol": 1e-14,
                     "gtol": 1e-10},
        )  # fmt: skip
        weights, biases = _unpack(found.x, shapes)
        network = cls(
            tuple(weights), tuple(biases), mean_x, scale_x, mean_y, scale_y, float(rate_limit)
        )
        error = float(np.mean((network.raw(x) - y) ** 2) / scale_y**2)
        return network, error


def _shapes(inputs: int, hidden: tuple[int, ...]) -> list[tuple[int, int]]:
    """(rows, columns) of each weight matrix."""
    widths = [inputs, *hidden, 1]
    return list(zip(widths[1:], widths[:-1], strict=True))


def _unpack(theta: np.ndarray, shapes) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Weights and biases from the flat parameters (each layer's W row-major, then its b)."""
    weights, biases, at = [], [], 0
    for rows, columns in shapes:
        weights.append(theta[at : at + rows * columns].reshape(rows, columns))
        at += rows * columns
        biases.append(theta[at : at + rows])
        at += rows
    return weights, biases


def _loss(theta: np.ndarray, x: np.ndarray, y: np.ndarray, shapes) -> tuple[float, np.ndarray]:
    """Half the mean squared error plus the weight decay, and its gradient (backpropagation)."""
    weights, biases = _unpack(theta, shapes)
    layers = [x]
    for w, b in zip(weights[:-1], biases[:-1], strict=True):
        layers.append(np.tanh(layers[-1] @ w.T + b))
    residual = (layers[-1] @ weights[-1].T + biases[-1])[:, 0] - y
    count = y.size
    loss = 0.5 * float(residual @ residual) / count
    loss += 0.5 * DECAY * sum(float(np.sum(w * w)) for w in weights)
    back = residual[:, None] / count
    grads = []
    for k in range(len(weights) - 1, -1, -1):
        grads.append((back.sum(axis=0), back.T @ layers[k] + DECAY * weights[k]))
        if k:
            back = (back @ weights[k]) * (1.0 - layers[k] ** 2)
    gradient = np.concatenate([p for b, w in reversed(grads) for p in (w.ravel(), b)])
    return loss, gradient
