"""rbm_nb._infra"""
