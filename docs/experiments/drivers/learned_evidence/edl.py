"""A small evidential MLP in numpy: forward, the EDL loss of Sensoy et al. 2018 (NeurIPS,
"Evidential Deep Learning to Quantify Classification Uncertainty", eq. 5 plus the annealed KL
term) with its gradient, and Adam. Development-only; the C++ side only runs the forward pass
(src/evidence/learned_evidence.cpp)."""
import numpy as np


def softplus(z):
    return np.where(z > 20.0, z, np.log1p(np.exp(np.minimum(z, 20.0))))


def sigmoid(z):
    return 1.0 / (1.0 + np.exp(-np.clip(z, -30.0, 30.0)))


def trigamma(x):
    """psi_1(x) for x > 0: recurrence up to x >= 6, then the asymptotic series."""
    x = np.asarray(x, dtype=np.float64).copy()
    acc = np.zeros_like(x)
    small = x < 6.0
    while small.any():
        acc[small] += 1.0 / (x[small] * x[small])
        x[small] += 1.0
        small = x < 6.0
    inv = 1.0 / x
    inv2 = inv * inv
    series = inv + 0.5 * inv2 + inv * inv2 * (1.0 / 6 - inv2 * (1.0 / 30 - inv2 * (1.0 / 42 - inv2 / 30)))
    return acc + series


class Mlp:
    """x -> (x - mean) / std -> [dense + relu] * (L-1) -> dense + softplus = evidence."""

    def __init__(self, sizes, rng):
        self.w = [rng.normal(0, np.sqrt(2.0 / a), (b, a)).astype(np.float32)
                  for a, b in zip(sizes[:-1], sizes[1:])]
        self.b = [np.zeros(b, np.float32) for b in sizes[1:]]
        self.mean = np.zeros(sizes[0], np.float32)
        self.std = np.ones(sizes[0], np.float32)

    def params(self):
        return self.w + self.b

    def forward(self, x, keep=False):
        a = (x - self.mean) / self.std
        cache = [a]
        for k, (w, b) in enumerate(zip(self.w, self.b)):
            z = a @ w.T + b
            if k + 1 < len(self.w):
                a = np.maximum(z, 0.0)
                cache.append(a)
            else:
                cache.append(z)
                a = softplus(z)
        return (a, cache) if keep else a

    def backward(self, cache, grad_z_out):
        """Gradients of the parameters given dL/d(output pre-activation)."""
        gw, gb = [None] * len(self.w), [None] * len(self.b)
        g = grad_z_out
        for k in reversed(range(len(self.w))):
            a_in = cache[k]
            gw[k] = g.T @ a_in
            gb[k] = g.sum(axis=0)
            if k > 0:
                g = (g @ self.w[k]) * (cache[k] > 0)
        return gw + gb


def edl_loss_grad(z, y, kl_weight, sample_weight):
    """Mean over the batch of w_i [MSE-EDL(alpha_i, y_i) + kl_weight KL(Dir(alpha~_i) || Dir(1))]
    and its gradient w.r.t. the output pre-activation z (evidence = softplus(z)).
    y: int class ids. Returns (loss without KL, gradient)."""
    n, k = z.shape
    e = softplus(z).astype(np.float64)
    alpha = e + 1.0
    s = alpha.sum(axis=1, keepdims=True)
    p = alpha / s
    onehot = np.zeros_like(p)
    onehot[np.arange(n), y] = 1.0
    q = (p * p).sum(axis=1, keepdims=True)
    p_y = p[np.arange(n), y][:, None]
    loss = ((onehot - p) ** 2).sum(axis=1) + ((1.0 - q) / (s + 1.0))[:, 0]
    # dL/dalpha_j = 2 (p_j - Q)/(S+1) - 2 (y_j - p_y)/S - (1 - Q)/(S+1)^2
    g_alpha = 2.0 * (p - q) / (s + 1.0) - 2.0 * (onehot - p_y) / s - (1.0 - q) / (s + 1.0) ** 2
    if kl_weight > 0.0:
        # alpha~ = y + (1 - y) alpha; dKL/dalpha~_j = (alpha~_j - 1) psi1(alpha~_j) - (S~ - K) psi1(S~)
        at = onehot + (1.0 - onehot) * alpha
        st = at.sum(axis=1, keepdims=True)
        g_kl = (at - 1.0) * trigamma(at) - (st - k) * trigamma(st)
        g_alpha += kl_weight * g_kl * (1.0 - onehot)
    w = sample_weight[:, None] / n
    g_z = g_alpha * w * sigmoid(z)
    return float((loss * sample_weight).mean()), g_z.astype(np.float32)


class Adam:
    def __init__(self, params, lr=1e-3, beta1=0.9, beta2=0.999, eps=1e-8, weight_decay=1e-4):
        self.lr, self.b1, self.b2, self.eps, self.wd = lr, beta1, beta2, eps, weight_decay
        self.m = [np.zeros_like(p) for p in params]
        self.v = [np.zeros_like(p) for p in params]
        self.t = 0

    def step(self, params, grads):
        self.t += 1
        for p, g, m, v in zip(params, grads, self.m, self.v):
            if p.ndim == 2:
                g = g + self.wd * p
            m *= self.b1
            m += (1 - self.b1) * g
            v *= self.b2
            v += (1 - self.b2) * g * g
            mhat = m / (1 - self.b1 ** self.t)
            vhat = v / (1 - self.b2 ** self.t)
            p -= (self.lr * mhat / (np.sqrt(vhat) + self.eps)).astype(p.dtype)
